// Flamenco job type "mcrecon" (issue 19): denoise a rendered sequence in chunks, one task per
// chunk, each running the command `mcrecon plan` prints for it (with warm-up and --resume).
//
// Written for Flamenco 3.x's job compiler API as its manual documents it (usage/job-types,
// usage/jobs-tasks-commands/commands): a JOB_TYPE object, compileJob(job), the globals author.Task,
// author.Command, frameChunker, and the worker command "exec" {exe, args}, run without a shell.
// Not run here: no Flamenco Manager or Worker in this project's tests (see farm/README.md).
// Install: copy to scripts/mcrecon.js next to flamenco-manager; the job type is the file name.

const JOB_TYPE = {
    label: "mcrecon denoise",
    settings: [
        { key: "exe", type: "string", default: "mcrecon",
          description: "mcrecon CLI on the workers (a path, or a Flamenco variable such as {mcrecon})" },
        { key: "input", type: "string", subtype: "file_path", required: true,
          description: "Noisy sequence, a pattern: /shared/shot/beauty_####.exr" },
        { key: "output", type: "string", subtype: "file_path", required: true,
          description: "Denoised sequence, a pattern: /shared/shot/denoised_####.exr" },
        { key: "filter", type: "string", default: "bmfr",
          choices: ["bmfr", "auto", "box", "gaussian", "bilateral", "atrous", "guided", "pwaf", "sweep"],
          description: "mcrecon filter (bmfr is temporal: give it a warm-up)" },
        { key: "frames", type: "string", required: true,
          eval: "f'{C.scene.frame_start}-{C.scene.frame_end}'",
          description: "Frames to denoise: 1-240 or 1-100,120-240 (no x/y steps: frameChunker reads none)" },
        { key: "chunk_size", type: "int32", default: 24, propargs: { min: 1 },
          description: "Frames per task" },
        { key: "warmup", type: "int32", default: 8, propargs: { min: 0 },
          description: "Frames of history each chunk runs before its first frame (bmfr: 8; others: 0)" },
        { key: "extra_args", type: "string", default: "",
          description: "More denoise arguments, split at spaces (no quoting): -s taa=false --compression piz" },
        { key: "check_script", type: "string", subtype: "file_path", default: "",
          description: "farm/slurm/mcrecon_check.py on shared storage: a last task checks every frame" },
    ]
};

function firstFrame(frames) {
    // "25-48" or "239,240" (frameChunker's chunks): the number they start with.
    const n = parseInt(frames, 10);
    if (isNaN(n)) throw `mcrecon: cannot read a first frame in "${frames}"`;
    return n;
}

function compileJob(job) {
    const s = job.settings;
    // The arguments after `--` in `mcrecon plan`; array elements, never a shell line.
    const denoise = ["denoise", s.input, "-o", s.output, "-f", s.filter]
        .concat(s.extra_args.split(" ").filter((a) => a.length > 0));
    const start = firstFrame(s.frames);
    const chunkTasks = [];

    for (const chunk of frameChunker(s.frames, s.chunk_size)) {
        // As `mcrecon plan`: the warm-up a chunk can have (none before the sequence starts), and
        // --resume, so a task the Manager requeues keeps the frames a first try finished.
        const warmup = Math.min(s.warmup, firstFrame(chunk) - start);
        const args = denoise.concat(["--frames", chunk]);
        if (warmup > 0) args.push("--warmup", String(warmup));
        args.push("--resume");

        // "misc": a type the workers run by default; name your own to route mcrecon tasks.
        const task = author.Task(`denoise-${chunk}`, "misc");
        task.addCommand(author.Command("exec", { exe: s.exe, args: args }));
        job.addTask(task);
        chunkTasks.push(task);
    }

    if (s.check_script) {
        // The Slurm recipe's check (env vars in, no shell): every output exists and reads.
        const check = author.Task("check-outputs", "misc");
        check.addCommand(author.Command("exec", {
            exe: "/usr/bin/env",
            args: [`MCRECON=${s.exe}`, `FRAMES=${s.frames}`, "python3", s.check_script].concat(denoise),
        }));
        for (const t of chunkTasks) check.addDependency(t);
        job.addTask(check);
    }
}

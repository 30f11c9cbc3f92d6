// mcrecon plan: split a sequence's denoise into chunks for a farm, each a command that
// matches its part of a single run (--warmup) and is safe to requeue (--resume).
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "io/sequence.h"
#include "pipeline/denoise_session.h"
#include "pipeline/reconstruction.h"
#include "pipeline/sequence_plan.h"
#include "util/error.h"

namespace mcr::cli {

namespace {

struct PlanArgs {
  std::string frames, exe = "mcrecon";
  int chunk = 0, warmup = 0, task = 0;
  bool json = false;
  std::vector<std::string> command;  // after --: denoise and its arguments
};

// POSIX shell quoting: bare when only safe characters, else in single quotes.
std::string quoted(const std::string& s) {
  const bool safe = !s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                                                      "@%+=:,./-_#") == std::string::npos;
  if (safe) return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

int run_plan(const PlanArgs& a) {
  if (a.command.empty() || a.command[0] != "denoise")
    throw Error(Errc::InvalidArgument, "plan: give the denoise command after --, e.g. mcrecon plan --frames 1-240 "
                                       "--chunk 24 --warmup 8 -- denoise shot_####.exr -o out_####.exr -f bmfr");
  for (const std::string& arg : a.command)
    for (const char* own : {"--frames", "--warmup", "--resume"})
      if (arg == own || arg.rfind(std::string(own) + "=", 0) == 0)
        throw Error(Errc::InvalidArgument, "plan: '" + arg + "' after --: plan gives each chunk its own " + own);
  // The filter and its settings checked here, before a farm queues a task that would fail.
  std::string filter;
  std::vector<std::pair<std::string, std::string>> sets;
  for (std::size_t i = 1; i + 1 < a.command.size(); ++i) {
    const std::string& arg = a.command[i];
    if (arg == "-f" || arg == "--filter") filter = a.command[i + 1];
    if (arg == "-s" || arg == "--set") sets.push_back(parse_key_value(a.command[i + 1], "--set"));
  }
  for (const std::string& arg : a.command) {
    if (arg.rfind("--filter=", 0) == 0) filter = arg.substr(9);
    if (arg.rfind("--set=", 0) == 0) sets.push_back(parse_key_value(arg.substr(6), "--set"));
  }
  if (filter.empty()) throw Error(Errc::InvalidArgument, "plan: the denoise command after -- names no filter (-f NAME)");
  make_committed_filter(filter, sets);
  const FrameList frames = parse_frame_list(a.frames);
  const std::vector<Chunk> chunks = plan_chunks(frames, a.chunk, a.warmup);
  if (a.task < 0 || a.task > int(chunks.size()))
    throw Error(Errc::InvalidArgument, "--task " + std::to_string(a.task) + ": the plan has chunks 1 to " +
                                           std::to_string(chunks.size()));
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t i = 0; i < chunks.size(); ++i) {
    if (a.task && int(i) + 1 != a.task) continue;
    const Chunk& c = chunks[i];
    std::vector<std::string> argv = {a.exe};
    argv.insert(argv.end(), a.command.begin(), a.command.end());
    argv.insert(argv.end(), {"--frames", c.frames.text()});
    if (c.warmup > 0) argv.insert(argv.end(), {"--warmup", std::to_string(c.warmup)});
    argv.push_back("--resume");
    if (a.json) {
      list.push_back({{"task", i + 1}, {"frames", c.frames.text()}, {"first", c.frames.first()},
                      {"last", c.frames.last()}, {"count", c.frames.size()}, {"warmup", c.warmup}, {"argv", argv}});
      continue;
    }
    std::string line;
    for (const std::string& s : argv) line += (line.empty() ? "" : " ") + quoted(s);
    std::cout << line << "\n";
  }
  if (a.json) std::cout << list.dump(1) << "\n";
  return 0;
}

}  // namespace

Run add_plan(CLI::App& app) {
  auto a = std::make_shared<PlanArgs>();
  app.add_option("--frames", a->frames, "the whole sequence's frames (1-240, 1-240x2, ...)")->required();
  app.add_option("--chunk", a->chunk, "frames per chunk (one farm task each)")->required()->check(CLI::Range(1, 1000000));
  app.add_option("--warmup", a->warmup,
                 "frames of history each chunk runs before its first frame (temporal filters; bmfr: 8)")
      ->check(CLI::Range(0, 1000000));
  app.add_option("--task", a->task, "print only chunk K (1-based, e.g. a Slurm array task id)")->check(CLI::Range(1, 1000000));
  app.add_option("--exe", a->exe, "the mcrecon the commands run")->capture_default_str();
  app.add_flag("--json", a->json, "the chunks as JSON (task, frames, warmup, argv) for a farm engine");
  app.add_option("command", a->command, "after --: denoise and its arguments, without --frames, --warmup, --resume")
      ->required();
  return [a] { return run_plan(*a); };
}

}  // namespace mcr::cli

// mcrecon.report(): the engine of `mcrecon report` from Python (same options, same files).
#include "report_binding.h"

#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <sstream>

#include "report/report.h"
#include "util/error.h"

namespace py = pybind11;

namespace {

// $MCRECON_BIN, else `mcrecon` on PATH: the CLI that command timing runs.
std::string find_cli() {
  if (const char* env = std::getenv("MCRECON_BIN")) return env;
  if (const char* path = std::getenv("PATH")) {
    std::stringstream dirs(path);
    for (std::string d; std::getline(dirs, d, ':');) {
      const std::filesystem::path p = std::filesystem::path(d) / "mcrecon";
      if (std::filesystem::is_regular_file(p)) return p.string();
    }
  }
  return "";
}

mcr::ReportInput input_from_dict(const py::dict& d) {
  mcr::ReportInput in;
  for (const auto& [key, value] : d) {
    const std::string k = py::str(key);
    if (k == "noisy" || k == "input") in.noisy = py::str(value);
    else if (k == "reference") in.reference = py::str(value);
    else if (k == "frames") in.frames = py::str(value);
    else if (k == "name") in.name = py::str(value);
    else if (k == "spp") in.spp = value.cast<int>();
    else
      throw mcr::Error(mcr::Errc::InvalidArgument,
                       "inputs: unknown key '" + k + "' (known: noisy, reference, frames, name, spp)");
  }
  if (in.noisy.empty() || in.reference.empty())
    throw mcr::Error(mcr::Errc::InvalidArgument, "inputs: each needs 'noisy' and 'reference'");
  return in;
}

}  // namespace

void add_report_binding(py::module_& m) {
  m.def(
      "report",
      [](const std::string& out, const std::optional<std::string>& samples, const std::vector<int>& spp,
         const std::vector<std::string>& scenes, const std::vector<std::string>& filters, const py::list& inputs,
         const std::vector<std::string>& peers, bool builtin_peers, const std::string& timing, bool sweeps,
         int scaling_max, int scaling_min, int threads, int repeat, const std::optional<std::string>& cli,
         const std::string& python, bool page, bool with_samples,
         const std::optional<std::function<void(std::string)>>& progress) {
        mcr::ReportOptions o;
        o.out = out;
        o.samples = samples.value_or("");
        o.spp = spp;
        o.scenes = scenes;
        o.filters = filters;
        for (const auto& item : inputs) o.inputs.push_back(input_from_dict(item.cast<py::dict>()));
        o.with_samples = o.inputs.empty() || with_samples;
        o.peers = peers;
        o.builtin_peers = builtin_peers;
        o.timing = timing;
        o.sweeps = sweeps;
        o.scaling_max = scaling_max;
        o.scaling_min = scaling_min;
        o.threads = threads;
        o.repeat = repeat;
        o.cli = cli.value_or(find_cli());
        o.python = python;
        if (progress)
          o.log = [&progress](const std::string& line) {
            py::gil_scoped_acquire hold;
            (*progress)(line);
          };
        mcr::ReportSummary s;
        std::string html;
        {
          py::gil_scoped_release release;
          s = mcr::run_report(o);
          if (page) html = mcr::render_report_page(o);
        }
        py::dict r;
        r["results_json"] = s.results_json;
        r["results_csv"] = s.results_csv;
        r["report_html"] = page ? py::object(py::str(html)) : py::object(py::none());
        r["scenes"] = s.scenes;
        r["runs"] = s.runs;
        r["failed_runs"] = s.failed_runs;
        return r;
      },
      py::arg("out"), py::kw_only(), py::arg("samples") = py::none(), py::arg("spp") = std::vector<int>{16},
      py::arg("scenes") = std::vector<std::string>{}, py::arg("filters") = std::vector<std::string>{},
      py::arg("inputs") = py::list(), py::arg("peers") = std::vector<std::string>{}, py::arg("builtin_peers") = true,
      py::arg("timing") = "auto", py::arg("sweeps") = true, py::arg("scaling_max") = 2048,
      py::arg("scaling_min") = 256, py::arg("threads") = 0, py::arg("repeat") = 1, py::arg("cli") = py::none(),
      py::arg("python") = "/usr/bin/python3", py::arg("page") = true, py::arg("with_samples") = false,
      py::arg("progress") = py::none(),
      "The engine of `mcrecon report`: writes OUT/results.json, results.csv, the pictures and (page=True) "
      "report.html. inputs: [{'noisy': ..., 'reference': ..., 'frames': '1-16', 'name': ..., 'spp': 16}]; peers: "
      "['oidn=oidnDenoise --hdr {colour} -o {output}']; cli: the mcrecon CLI for command timing (default "
      "$MCRECON_BIN or mcrecon on PATH); progress(line). Returns the paths and the counts of scenes, runs and "
      "failed runs.");
}

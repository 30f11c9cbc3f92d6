#pragma once
// External denoisers in the report ("peers"): a command template with the input's passes
// exported for it, run without a shell and timed as a process.
#include <string>
#include <vector>

#include "image/pass.h"

namespace mcr {

struct PeerCommand {
  std::string name;
  std::vector<std::string> words;  // the template, split like a POSIX shell would (quotes, backslashes)
};

// "oidn=oidnDenoise --hdr {colour} -o {output}". Throws InvalidArgument naming --peer and the
// text: no name, an empty or unbalanced template, no {output}, an unknown placeholder.
PeerCommand parse_peer(const std::string& text);

// The passes a template names ({colour}, {albedo}, {normal}, {depth}, {position}).
std::vector<Role> peer_roles(const PeerCommand& peer);

// The command for one frame: each {pass} / {pass.exr} / {pass.pfm} replaced by the file the
// pass is exported to under `dir` (written here, PFM unless .exr is asked for), {output} /
// {output.exr} / {output.pfm} by the file the peer must write (returned in `output`).
// Throws MissingPass when the frame lacks a pass the template names.
std::vector<std::string> peer_argv(const PeerCommand& peer, const Frame& frame, const std::string& dir,
                                   std::string& output);

struct CommandRun {
  double seconds = 0;          // wall clock, spawn to exit
  double peak_memory_mb = -1;  // the process's peak resident size (its rusage)
  int exit_code = 0;           // -signal when killed by one
  bool timed_out = false;
};

// Runs argv[0] (looked up on PATH) with stdout and stderr appended to `log` ("": the caller's
// own, for a child whose progress the user should see), waits at most
// `timeout_seconds` (then kills it). Throws Internal when it cannot be started.
CommandRun run_timed_command(const std::vector<std::string>& argv, const std::string& log, double timeout_seconds);

// A log file's whole text ("" when it cannot be read).
std::string read_log(const std::string& log);
// The last `max_chars` of a log file, for error messages.
std::string log_tail(const std::string& log, std::size_t max_chars = 600);

}  // namespace mcr

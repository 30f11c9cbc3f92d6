#pragma once
// Which frames a sequence run reads and which it writes: --resume (outputs already done are
// not redone, and a temporal filter replays only what its history needs) and --warmup
// (a chunk of a farm job starts with the history a single run would have).
#include <string>
#include <vector>

#include "io/sequence.h"

namespace mcr {

struct FrameJob {
  int frame = 0;
  bool write = true;  // false: read and filtered for the temporal history only
};

// frames: the run's frames; done[i]: frame i's output exists and is verified (--resume).
// temporal: the reconstruction keeps history (frames must then be consecutive). warmup: the
// history starts that many frames before the run's first frame (frames before the list are
// read, never written; < 0 is 0); with --resume every frame from there to the first one to
// write is replayed, so a requeued chunk gives the same pixels as its first, whole run.
// Not temporal: the frames not done, warmup ignored. Frames after the last one to write are
// never read, and nothing at all when every frame is done.
std::vector<FrameJob> plan_sequence(const FrameList& frames, const std::vector<bool>& done, bool temporal, int warmup);

// A sequence split for a farm: consecutive runs of at most `chunk` frames of the list, each
// with the warm-up its first frame needs (min(warmup, frames before it in the list's span):
// the first chunk none, as a single run has none).
struct Chunk {
  FrameList frames;
  int warmup = 0;
};
std::vector<Chunk> plan_chunks(const FrameList& frames, int chunk, int warmup);

// What an output's header records of the input it was made from: "<file name> <size> bytes".
std::string input_stamp(const std::string& input);

// "" when the existing `output` can be kept by --resume: it reads completely and its header
// (mcreconFilter, mcreconParameters, mcreconInput) names this filter, these parameters and
// this input; otherwise why it must be redone, e.g. "made by atrous, this run is bmfr".
std::string stale_output_reason(const std::string& output, const std::string& filter, const std::string& parameters,
                                const std::string& input);

}  // namespace mcr

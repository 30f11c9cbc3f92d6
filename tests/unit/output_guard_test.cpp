// The output guard (io/output_guard.h) and the temp + rename writer (io/atomic_write.h):
// never over an input, only regular files or new paths, every frame its own file, unique
// temps that fit NAME_MAX, concurrent writers, dead runs' temps, disk full.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "expect_error.h"
#include "io/atomic_write.h"
#include "io/output_guard.h"
#include "io/sequence.h"
#include "pipeline/denoise_session.h"
#include "scratch_dir.h"
#include "util/error.h"

namespace mcr {
namespace {

namespace fs = std::filesystem;
using Names = std::vector<std::string>;
using testutil::contains;
using testutil::expect_error;
using testutil::ScratchDir;

// A w x h RGB float image, every value v.
OIIO::ImageBuf constant_image(int w, int h, float v) {
  OIIO::ImageBuf buf(OIIO::ImageSpec(w, h, 3, OIIO::TypeFloat));
  std::vector<float> px(std::size_t(w) * h * 3, v);
  buf.set_pixels(buf.roi(), OIIO::TypeFloat, px.data());
  return buf;
}

std::string bytes_of(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Every pixel value of an EXR (empty when it cannot be read).
std::vector<float> pixels_of(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return {};
  const OIIO::ImageSpec& s = in->spec();
  std::vector<float> px(std::size_t(s.width) * s.height * s.nchannels);
  if (!in->read_image(0, 0, 0, s.nchannels, OIIO::TypeFloat, px.data())) return {};
  return px;
}

// A character device node (1,3: what /dev/null is) private to the test, never the real one.
bool make_device_node(const std::string& path) { return ::mknod(path.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0; }

bool is_char_device(const std::string& path) {
  struct stat st;
  return ::lstat(path.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

TEST(SequencePath, HashRunsOfAnyWidthAreNeverCut) {
  const std::string run(40, '#');
  EXPECT_EQ(sequence_path("f_" + run + ".exr", 1), "f_" + std::string(39, '0') + "1.exr");
  EXPECT_NE(sequence_path("f_" + run + ".exr", 1), sequence_path("f_" + run + ".exr", 2));
  EXPECT_EQ(sequence_path("f_####.exr", -5), "f_-005.exr");  // printf's %04d
  EXPECT_EQ(sequence_path("f_#.exr", -2147483647 - 1), "f_-2147483648.exr");
  EXPECT_EQ(sequence_path("f_%04d.exr", -5), "f_-005.exr");
}

TEST(OutputGuard, SequenceOutputsAreDistinctAndNeverAnInput) {
  ScratchDir dir("mcrecon_guard");
  std::ofstream(dir.path("in_0002.exr")) << "render";
  const std::vector<std::string> inputs = {dir.path("in_0001.exr"), dir.path("in_0002.exr")};
  check_sequence_outputs(dir.path("out_" + std::string(40, '#') + ".exr"), FrameList::span(1, 2), inputs);  // wide: fine

  // Every frame onto one file through "..": the pattern and both frames are named.
  fs::create_directories(dir.path("d_0001"));
  const std::string pattern = dir.path("d_####/../out.exr");
  std::string msg = expect_error(Errc::InvalidArgument, [&] { check_sequence_outputs(pattern, FrameList::span(1, 3), inputs); });
  EXPECT_TRUE(contains(msg, pattern) && contains(msg, "frames 1 and 2")) << msg;

  msg = expect_error(Errc::InvalidArgument,
                     [&] { check_sequence_outputs(dir.path("./in_####.exr"), FrameList::span(1, 2), inputs); });
  EXPECT_TRUE(contains(msg, "in_0001.exr") && contains(msg, "never overwritten")) << msg;
  // Outputs given as a list: two spellings of one file.
  msg = expect_error(Errc::InvalidArgument,
                     [&] { check_output_paths({dir.path("a.exr"), dir.path("d_0001/../a.exr")}, {}); });
  EXPECT_TRUE(contains(msg, "a.exr")) << msg;
  EXPECT_EQ(dir.listing(), (Names{"d_0001", "in_0002.exr"}));
}

TEST(OutputGuard, OnlyRegularFilesOrNewPathsAreWritten) {
  ScratchDir dir("mcrecon_guard");
  const std::string node = dir.path("null"), fifo = dir.path("fifo"), sock = dir.path("sock");
  if (!make_device_node(node)) GTEST_SKIP() << "mknod: " << std::strerror(errno) << " (needs root)";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0666), 0);
  const int s = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, sock.c_str(), sizeof addr.sun_path - 1);
  ASSERT_EQ(::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0) << sock;
  fs::create_directories(dir.path("sub"));
  fs::create_symlink(node, dir.path("link_to_null"));
  const OIIO::ImageBuf img = constant_image(4, 3, 0.5f);

  const std::pair<std::string, std::string> cases[] = {{node, "character device"}, {fifo, "FIFO"}, {sock, "socket"},
                                                       {dir.path("sub"), "directory"},
                                                       {dir.path("link_to_null"), "character device"}};
  for (const auto& c : cases) {
    const std::string &target = c.first, &kind = c.second;  // named copies: lambdas cannot capture bindings
    for (const std::string& msg :
         {expect_error(Errc::WriteFailed, [&] { check_output_path(target, {}); }),
          expect_error(Errc::WriteFailed, [&] { write_atomic(img, target, "openexr"); }),
          expect_error(Errc::WriteFailed, [&] { write_text_atomic("x", target); })})
      EXPECT_TRUE(contains(msg, "'" + target + "'") && contains(msg, kind) && contains(msg, "regular file")) << msg;
  }
  ::close(s);
  EXPECT_TRUE(is_char_device(node));
  struct stat st;
  EXPECT_TRUE(::stat(fifo.c_str(), &st) == 0 && S_ISFIFO(st.st_mode));
  EXPECT_EQ(dir.listing(), (Names{"fifo", "link_to_null", "null", "sock", "sub"}));
}

// Every front end's file run: the session itself refuses to write over any input.
TEST(OutputGuard, DenoiseSessionNeverWritesOverAnInput) {
  ScratchDir dir("mcrecon_guard");
  write_atomic(constant_image(5, 4, 0.25f), dir.path("in.exr"));
  write_atomic(constant_image(5, 4, 0.75f), dir.path("n.exr"));
  fs::create_directories(dir.path("sub"));
  fs::create_symlink(dir.path("in.exr"), dir.path("link.exr"));
  fs::create_hard_link(dir.path("in.exr"), dir.path("hard.exr"));
  const std::string in_bytes = bytes_of(dir.path("in.exr")), n_bytes = bytes_of(dir.path("n.exr"));
  DenoiseSession session("box", {});
  ReadOptions with_pass;
  with_pass.overrides.push_back({Role::Normal, dir.path("n.exr")});
  const std::pair<std::string, std::string> cases[] = {
      {dir.path("in.exr"), "in.exr"},      {dir.path("./in.exr"), "in.exr"}, {dir.path("sub/../in.exr"), "in.exr"},
      {dir.path("link.exr"), "link.exr"}, {dir.path("hard.exr"), "hard.exr"}};
  for (const auto& c : cases) {
    const std::string &output = c.first, &named = c.second;
    const std::string msg =
        expect_error(Errc::InvalidArgument, [&] { session.run(dir.path("in.exr"), output, {}, {}, {}); });
    EXPECT_TRUE(contains(msg, named) && contains(msg, "never overwritten")) << msg;
  }
  const std::string msg =
      expect_error(Errc::InvalidArgument, [&] { session.run(dir.path("in.exr"), dir.path("n.exr"), with_pass, {}, {}); });
  EXPECT_TRUE(contains(msg, "n.exr")) << msg;
  EXPECT_EQ(bytes_of(dir.path("in.exr")), in_bytes);
  EXPECT_EQ(bytes_of(dir.path("n.exr")), n_bytes);
  EXPECT_EQ(dir.listing(), (Names{"hard.exr", "in.exr", "link.exr", "n.exr", "sub"}));
  session.run(dir.path("in.exr"), dir.path("out.exr"), with_pass, {}, {});  // a new path: fine
  EXPECT_EQ(pixels_of(dir.path("out.exr")).size(), 5u * 4u * 4u);
}

// Two writers on one output: both succeed, the last rename wins, the file is always one
// writer's complete image, and no temp is left.
TEST(OutputGuard, ConcurrentWritersOfOneOutputAllSucceed) {
  ScratchDir dir("mcrecon_guard");
  const std::string out = dir.path("out.exr");
  constexpr int kThreads = 8, kRounds = 6;
  std::vector<std::string> errors(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      const OIIO::ImageBuf img = constant_image(64, 48, float(t + 1));
      try {
        for (int r = 0; r < kRounds; ++r) write_atomic(img, out);
      } catch (const std::exception& e) {
        errors[std::size_t(t)] = e.what();
      }
    });
  for (auto& th : threads) th.join();
  for (const auto& e : errors) EXPECT_EQ(e, "");
  const std::vector<float> px = pixels_of(out);
  ASSERT_EQ(px.size(), 64u * 48u * 3u);
  EXPECT_GE(px[0], 1.0f);
  EXPECT_LE(px[0], float(kThreads));
  for (float v : px) ASSERT_EQ(v, px[0]) << "a mixed file";
  EXPECT_EQ(dir.listing(), (Names{"out.exr"}));
}

TEST(OutputGuard, OnlyTempsOfDeadRunsAreRemoved) {
  ScratchDir dir("mcrecon_guard");
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);  // its pid is now a dead run's
  const std::string prefix = temp_prefix_for(dir.path("out.exr"));
  EXPECT_EQ(prefix, ".out.exr.mcrecon-tmp.");
  const std::string dead = prefix + std::to_string(child) + ".0.0badf00d";
  const std::string old_style = prefix + std::to_string(child);  // earlier versions' name
  const std::string live = prefix + std::to_string(::getpid()) + ".99.12345678";
  const std::string other = ".other.exr.mcrecon-tmp." + std::to_string(child) + ".0.00000000";
  for (const auto& n : {dead, old_style, live, other}) std::ofstream(dir.path(n)) << "partial";
  write_atomic(constant_image(2, 2, 1.0f), dir.path("out.exr"));
  Names want = {live, other, "out.exr"};
  std::sort(want.begin(), want.end());
  EXPECT_EQ(dir.listing(), want);
}

TEST(OutputGuard, TempNamesFitNameMax) {
  ScratchDir dir("mcrecon_guard");
  for (std::size_t len : {200u, 254u, 255u}) {
    const std::string name = std::string(len - 4, 'n') + ".exr";
    // After the prefix: pid (10 digits at most), ".", counter (20), ".", 8 hex digits.
    EXPECT_LE(temp_prefix_for(name).size() + 40, std::size_t(NAME_MAX)) << len;
    write_atomic(constant_image(3, 2, 0.5f), dir.path(name));
    write_text_atomic("{}\n", dir.path(name));
    EXPECT_EQ(dir.listing(), (Names{name})) << len;
    fs::remove(dir.path(name));
  }
  // A UTF-8 name is cut between characters, never inside one.
  std::string utf8;
  while (utf8.size() < 250) utf8 += "\xc3\xa9";  // é
  const std::string prefix = temp_prefix_for(utf8);
  const std::string visible = prefix.substr(1, prefix.size() - 1 - std::strlen(".mcrecon-tmp."));
  EXPECT_EQ(visible.size() % 2, 0u) << visible.size();
}

TEST(OutputGuard, WriteErrorsNameTheCause) {
  EXPECT_EQ(write_error_text(ENOSPC), "the disk is full (" + std::string(std::strerror(ENOSPC)) + ")");
  EXPECT_TRUE(contains(write_error_text(EFBIG), "size limit"));
  EXPECT_TRUE(contains(write_error_text(EDQUOT), "quota"));
  EXPECT_EQ(write_error_text(EACCES), std::strerror(EACCES));
}

// A full disk: a small tmpfs (needs root and a mount namespace that allows it).
TEST(OutputGuard, DiskFullSaysSoAndLeavesNothing) {
  ScratchDir dir("mcrecon_guard");
  const std::string mnt = dir.path("small");
  fs::create_directories(mnt);
  if (::mount("tmpfs", mnt.c_str(), "tmpfs", 0, "size=64k") != 0) GTEST_SKIP() << "mount: " << std::strerror(errno);
  struct Unmount {
    std::string at;
    ~Unmount() { ::umount2(at.c_str(), MNT_DETACH); }
  } unmount{mnt};
  const std::string out = mnt + "/big.exr";
  OIIO::ImageBuf big(OIIO::ImageSpec(256, 256, 3, OIIO::TypeFloat));  // 768 KB, noise: no compression helps
  std::vector<float> px(256u * 256u * 3u);
  unsigned x = 12345;
  for (float& v : px) v = float((x = x * 1103515245u + 12345u) >> 8);
  big.set_pixels(big.roi(), OIIO::TypeFloat, px.data());
  std::string msg = expect_error(Errc::WriteFailed, [&] { write_atomic(big, out); });
  EXPECT_TRUE(contains(msg, "'" + out + "'") && contains(msg, "the disk is full") &&
              contains(msg, std::strerror(ENOSPC)))
      << msg;
  std::string text(200000, 'x');
  msg = expect_error(Errc::WriteFailed, [&] { write_text_atomic(text, mnt + "/big.json"); });
  EXPECT_TRUE(contains(msg, "the disk is full")) << msg;
  EXPECT_TRUE(fs::is_empty(mnt));
}

}  // namespace
}  // namespace mcr

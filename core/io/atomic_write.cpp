#include "io/atomic_write.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <random>

#include "util/error.h"

namespace mcr {

namespace fs = std::filesystem;

namespace {

// The temps being written, readable from a signal handler: one slot per write in
// flight (threads of the Python module may write several at once).
struct Slot {
  std::atomic<int> state{0};  // 0 free, 1 being filled, 2 holds a temp path
  char path[PATH_MAX];
};
static_assert(std::atomic<int>::is_always_lock_free, "signal handlers need lock-free atomics");
constexpr int kSlots = 32;
Slot g_slots[kSlots];

int claim_slot(const std::string& p) {
  if (p.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (!g_slots[i].state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(g_slots[i].path, p.c_str(), p.size() + 1);
    g_slots[i].state.store(2);
    return i;
  }
  return -1;  // more writes in flight than slots: that temp is not removed on a signal
}

// ".mcrecon-tmp." (13) + pid (10 digits at most) + "." + counter (20) + "." + 8 hex digits.
constexpr std::size_t kTailMax = 13 + 10 + 1 + 20 + 1 + 8;
constexpr const char* kMarker = ".mcrecon-tmp.";

// The visible part of a temp name: the target's name, cut (at a UTF-8 character
// boundary) so that "." + it + the tail fits NAME_MAX.
std::string visible_part(const std::string& name) {
  std::size_t n = std::min(name.size(), std::size_t(NAME_MAX) - 1 - kTailMax);
  while (n > 0 && n < name.size() && (static_cast<unsigned char>(name[n]) & 0xC0) == 0x80) --n;
  return name.substr(0, n);
}

fs::path dir_of(const std::string& path) {
  const fs::path d = fs::path(path).parent_path();
  return d.empty() ? fs::path(".") : d;
}

std::string unique_suffix() {
  static std::atomic<unsigned long> counter{0};
  static std::mutex mutex;
  static std::mt19937 rng{std::random_device{}()};
  unsigned r;
  {
    std::lock_guard<std::mutex> lock(mutex);
    r = unsigned(rng());
  }
  char buf[48];
  std::snprintf(buf, sizeof buf, "%ld.%lu.%08x", long(::getpid()), counter.fetch_add(1), r);
  return buf;
}

// Temps of this target left by runs that were killed: the owning pid is encoded in
// the name, and only the temps of processes that no longer exist are removed (a
// concurrent run's temp is live and stays).
void remove_stale_temps(const std::string& path) {
  const std::string prefix = temp_prefix_for(path);
  std::error_code ec;
  fs::directory_iterator it(dir_of(path), ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::size_t digits = name.find_first_not_of("0123456789", prefix.size());
    const std::string pid_text = name.substr(prefix.size(), digits == std::string::npos ? digits : digits - prefix.size());
    if (pid_text.empty() || pid_text.size() > 9 || (digits != std::string::npos && name[digits] != '.')) continue;
    const long pid = std::stol(pid_text);
    if (pid <= 0 || ::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;  // alive (or not ours to judge)
    struct stat st;
    if (::lstat(it->path().c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::unlink(it->path().c_str());
  }
}

// A temp file of this run, created exclusively; removed unless committed.
class TempFile {
 public:
  explicit TempFile(const std::string& target) : target_(target) {
    const fs::path dir = dir_of(target);
    for (int attempt = 0; fd_ < 0; ++attempt) {
      path_ = (dir / (temp_prefix_for(target) + unique_suffix())).string();
      fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd_ < 0 && (errno != EEXIST || attempt == 100))
        throw Error(Errc::WriteFailed, "cannot write '" + target + "': cannot create a temp file in '" +
                                           dir.string() + "': " + write_error_text(errno));
    }
    slot_ = claim_slot(path_);
  }
  ~TempFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!committed_) ::unlink(path_.c_str());
    if (slot_ >= 0) g_slots[slot_].state.store(0);
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  int fd() const { return fd_; }
  const std::string& path() const { return path_; }

  // Closes (reporting a late write error) and renames over the target.
  void commit() {
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail(errno);
    check_output_target(target_);  // replaced by a device or a directory meanwhile?
    if (::rename(path_.c_str(), target_.c_str()) != 0) fail(errno);
    committed_ = true;
  }
  [[noreturn]] void fail(int err) const {
    throw Error(Errc::WriteFailed, "cannot write '" + target_ + "': " + write_error_text(err));
  }

 private:
  std::string target_, path_;
  int fd_ = -1, slot_ = -1;
  bool committed_ = false;
};

// OIIO writes the file through this proxy to our exclusively created descriptor, so
// the first system error (ENOSPC, EFBIG, ...) is known exactly.
class FdOutput final : public OIIO::Filesystem::IOProxy {
 public:
  FdOutput(int fd, const std::string& name) : IOProxy(name, Write), fd_(fd) {}
  const char* proxytype() const override { return "mcrecon-fd"; }
  size_t write(const void* buf, size_t size) override {
    const size_t n = pwrite(buf, size, m_pos);
    m_pos += int64_t(n);
    return n;
  }
  size_t pwrite(const void* buf, size_t size, int64_t offset) override {
    std::lock_guard<std::mutex> lock(mutex_);
    size_t done = 0;
    while (done < size && err_ == 0) {
      const ssize_t n = ::pwrite(fd_, static_cast<const char*>(buf) + done, size - done, off_t(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) err_ = n < 0 ? errno : EIO;
      else done += size_t(n);
    }
    end_ = std::max(end_, size_t(offset) + done);
    return done;
  }
  size_t read(void*, size_t) override { return 0; }
  size_t pread(void*, size_t, int64_t) override { return 0; }
  size_t size() const override { return end_; }
  int err() const { return err_; }

 private:
  int fd_;
  std::mutex mutex_;
  size_t end_ = 0;
  int err_ = 0;
};

std::string format_for(const std::string& path, const std::string& format) {
  if (!format.empty()) return format;
  const std::string ext = fs::path(path).extension().string();
  if (ext.size() <= 1 || ext == ".exr") return "openexr";
  return ext.substr(1);
}

// Every writer's steps: guard the target, clear dead runs' temps, write a temp of
// our own, rename it over the target.
template <class Body>
void write_via_temp(const std::string& path, Body&& body) {
  if (path.empty()) throw Error(Errc::InvalidArgument, "no output path given");
  check_output_target(path);
  remove_stale_temps(path);
  TempFile tmp(path);
  body(tmp);
  tmp.commit();
}

}  // namespace

std::string temp_prefix_for(const std::string& path) {
  return "." + visible_part(fs::path(path).filename().string()) + kMarker;
}

void remove_pending_temp() noexcept {
  for (Slot& s : g_slots)
    if (s.state.load() == 2) ::unlink(s.path);
}

void write_atomic(const OIIO::ImageBuf& buf, const std::string& path, const std::string& format,
                  OIIO::TypeDesc dtype) {
  const std::string fmt = format_for(path, format);
  write_via_temp(path, [&](TempFile& tmp) {
    FdOutput proxy(tmp.fd(), tmp.path());  // outlives `out`, which may use it until destroyed
    auto out = OIIO::ImageOutput::create(fmt);
    if (!out) throw Error(Errc::WriteFailed, "cannot write '" + path + "': no writer for format '" + fmt + "'");
    if (!out->supports("ioproxy"))
      throw Error(Errc::Internal, "cannot write '" + path + "': the " + fmt + " writer takes no I/O proxy");
    out->set_ioproxy(&proxy);
    OIIO::ImageSpec spec = buf.spec();
    if (dtype != OIIO::TypeUnknown) spec.set_format(dtype);
    bool ok = out->open(tmp.path(), spec) && buf.write(out.get());
    ok = out->close() && ok;
    if (proxy.err()) tmp.fail(proxy.err());
    if (!ok) {
      std::string msg = out->geterror();
      if (const std::string b = buf.geterror(); !b.empty()) msg += (msg.empty() ? "" : "; ") + b;
      throw Error(Errc::WriteFailed, "cannot write '" + path + "': " + msg);
    }
  });
}

void write_fd_atomic(const std::string& path, const std::function<int(int fd)>& body) {
  write_via_temp(path, [&](TempFile& tmp) {
    if (const int err = body(tmp.fd())) tmp.fail(err);
  });
}

void write_text_atomic(const std::string& text, const std::string& path) {
  write_via_temp(path, [&](TempFile& tmp) {
    std::size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = ::write(tmp.fd(), text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) tmp.fail(n < 0 ? errno : EIO);
      done += std::size_t(n);
    }
  });
}

}  // namespace mcr

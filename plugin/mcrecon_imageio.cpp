// mcrecon.imageio: an OpenImageIO format plugin that runs an mcrecon filter.
//
// Input:  "render.exr.mcrecon?filter=box&radius=3" (or --iconfig mcrecon:KEY VALUE)
//         reads as the filtered R,G,B,A float image that `mcrecon denoise` writes.
// Output: "-o:fileformatname=mcrecon out.exr" with "mcrecon:KEY" attributes on the
//         image filters every channel it is given and writes a real EXR there.
// Both run a Reconstruction (accumulate=1: the accumulation stage before the filter)
// with per-stream history (history.h), and describe the run in the header:
// mcreconFilter, mcreconParameters, mcreconChosen (what filter auto ran), mcreconNotes (unused
// settings, the run's notes).
//
// OIIO 2.4 hazards this file is built around (see the shared notes):
// - OIIO 2.4 offers a file that failed its own reader to every reader, ours
//   included, while holding a non-recursive global lock: a foreign name is
//   rejected before any OIIO call, and open() never fails for a name of ours
//   (its errors are reported by the first pixel read), so OIIO never goes on to
//   that all-readers search with one of our names.
// - open() runs several times per input: it reads only the source's header; the
//   filter runs on the first pixel read, once per input (results are cached).
// - Our own locks are never held while OIIO may hold its lock and call us:
//   g_cache_mutex guards plain data only, g_run_mutex is taken only by pixel reads
//   and output writes, never by open()/valid_file().
#include <OpenImageIO/imageio.h>

#include <cstring>
#include <filesystem>
#include <list>
#include <memory>
#include <mutex>

#include "history.h"
#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "io/input_limits.h"
#include "io/output_guard.h"
#include "io/spec_window.h"
#include "pipeline/alpha_stage.h"
#include "pipeline/denoise_session.h"
#include "request.h"
#include "util/error.h"

OIIO_PLUGIN_NAMESPACE_BEGIN

namespace {

using mcr::Errc;
namespace mp = mcr::plugin;
namespace fs = std::filesystem;

// The one place a core error becomes an OIIO error: the CLI's message line.
std::string message(const std::exception& e) {
  if (dynamic_cast<const mcr::Error*>(&e)) return std::string("mcrecon: error: ") + e.what();
  return std::string("mcrecon: internal error: ") + e.what();
}

template <class T>
void report(const T& io, const std::exception& e) {
  io.errorfmt("{}", message(e));
}

// "mcrecon:KEY" attributes as text, in the spec's order.
mp::KeyValues plugin_attributes(const ImageSpec& spec) {
  mp::KeyValues kv;
  const std::size_t n = std::strlen(mp::kAttribPrefix);
  for (const ParamValue& p : spec.extra_attribs) {
    const std::string name = p.name().string();
    if (name.size() <= n || name.compare(0, n, mp::kAttribPrefix) != 0) continue;
    const std::string key = name.substr(n);
    if (key == "parameters" || key == "source" || key == "error") continue;  // our input's header, informational
    std::string value;
    if (p.type() == TypeInt) value = std::to_string(p.get_int());
    else if (p.type() == TypeFloat) value = mp::float_text(p.get_float());
    else value = p.get_string();
    kv.emplace_back(key, value);
  }
  return kv;
}

// Size and time of a file, so a re-rendered source is not served from a cache.
std::string file_stamp(const std::string& path) {
  std::error_code ec1, ec2;
  const auto size = fs::file_size(path, ec1);
  const auto time = fs::last_write_time(path, ec2);
  return std::to_string(ec1 ? 0 : size) + ":" + std::to_string(ec2 ? 0 : time.time_since_epoch().count());
}

struct Result {
  int width = 0, height = 0;
  std::vector<float> rgba;
  std::string notes;  // the reconstruction's notes after the run (mcreconNotes)
  std::string chosen;  // filter auto: what it ran (mcreconChosen)
};

std::mutex g_cache_mutex;  // guards g_results; never held across an OIIO call
std::list<std::pair<std::string, std::shared_ptr<const Result>>> g_results;  // most recent first
constexpr std::size_t kMaxResults = 2;

std::mutex g_run_mutex;  // one filter run at a time; guards g_history
mp::StreamHistory g_history;

std::shared_ptr<const Result> cached_result(const std::string& key) {
  std::lock_guard<std::mutex> lock(g_cache_mutex);
  for (auto it = g_results.begin(); it != g_results.end(); ++it)
    if (it->first == key) {
      g_results.splice(g_results.begin(), g_results, it);
      return it->second;
    }
  return nullptr;
}

void cache_result(const std::string& key, std::shared_ptr<const Result> r) {
  std::lock_guard<std::mutex> lock(g_cache_mutex);
  g_results.emplace_front(key, std::move(r));
  while (g_results.size() > kMaxResults) g_results.pop_back();
}

struct Filtered {
  mcr::Image rgb;
  mcr::Image alpha;  // the filtered alpha; empty where the input's is kept
  std::vector<mcr::ComponentImage> components;  // with r.keep_components: the light components
  std::string notes;  // mp::notes_text of the reconstruction's notes after the run
  std::string chosen;  // mcr::choices_text: what filter auto ran
};

// Runs the request's reconstruction (accumulation, filter) on one frame with the
// stream's history (see history.h).
Filtered run_filter(const mp::Request& r, const std::string& settings, const std::string& frame_name,
                    const mcr::Frame& frame) {
  auto lease = g_history.acquire(settings, frame_name, [&] { return mp::make_reconstruction(r); });
  try {
    Filtered f;
    if (r.keep_components) mcr::check_keep_components(lease.reconstruction->filter().params());
    f.rgb = lease.reconstruction->run(frame, {}, r.keep_components ? &f.components : nullptr, &f.alpha);
    f.notes = mp::notes_text(lease.reconstruction->notes());
    f.chosen = mcr::choices_text(lease.reconstruction->choices());
    g_history.done();
    return f;
  } catch (...) {
    g_history.failed();
    throw;
  }
}

// ---------------------------------------------------------------------------

class McreconInput final : public ImageInput {
 public:
  const char* format_name() const override { return mp::kFormat; }
  int supports(string_view feature) const override { return feature == "arbitrary_metadata"; }

  // Names only: no file access, no OIIO call (safe under OIIO's plugin lock).
  bool valid_file(const std::string& name) const override { return mp::is_plugin_name(name); }

  bool open(const std::string& name, ImageSpec& newspec) override { return open(name, newspec, ImageSpec()); }

  // Always succeeds for a name of ours. oiiotool answers a failed open of a name
  // that is not a file on disk ("x.exr.mcrecon?...") with its own "File does not
  // exist", hiding our message; so errors found here are kept and reported by the
  // first pixel read (and shown as the "mcreconError" attribute), and the spec
  // of a source that cannot be read is a 1x1 placeholder.
  bool open(const std::string& name, ImageSpec& newspec, const ImageSpec& config) override {
    if (!mp::is_plugin_name(name)) return false;  // foreign: before any OIIO call (2.4 deadlock)
    close();
    int width = 1, height = 1;
    mcr::PixelWindow window;
    std::string params_text, notes, chosen;
    try {
      auto [source, query] = mp::split_name(name);
      mp::KeyValues settings = plugin_attributes(config);
      settings.insert(settings.end(), query.begin(), query.end());
      request_ = mp::make_request(source, settings, false);
      // Unknown filter and parameter errors first, as in the CLI.
      const auto reconstruction = mp::make_reconstruction(request_);
      params_text = reconstruction->parameters_text();
      notes = mp::notes_text(reconstruction->notes());  // the unused settings, before any run
      settings_ = mp::settings_key(request_, params_text);
      key_ = settings_ + '\n' + source + '\n' + file_stamp(source);
      if (const auto done = cached_result(key_)) {  // plain data: no OIIO call
        notes = done->notes;
        chosen = done->chosen;
      }
      const ImageSpec src = source_header(source);
      width = src.width;
      height = src.height;
      window = mcr::window_of(src);
    } catch (const std::exception& e) {
      deferred_error_ = message(e);
    }
    // The layout write_result gives `mcrecon denoise` output: R,G,B,A float.
    m_spec = ImageSpec(width, height, 4, TypeFloat);
    mcr::set_window(m_spec, window);  // the source's, as `mcrecon denoise` writes them
    m_spec.channelnames = {"R", "G", "B", "A"};
    m_spec.alpha_channel = 3;
    m_spec.attribute("Software", "mcrecon");
    if (deferred_error_.empty()) {
      for (const auto& [name, value] : mcr::run_attributes(request_.filter, params_text, chosen, notes)) m_spec.attribute(name, value);
      m_spec.attribute("mcreconSource", request_.source);
    } else {
      m_spec.attribute("mcreconError", deferred_error_);
    }
    newspec = m_spec;
    open_ = true;
    return true;
  }

  bool close() override {
    open_ = false;
    deferred_error_.clear();
    result_.reset();
    return true;
  }

  bool read_native_scanline(int subimage, int miplevel, int y, int z, void* data) override {
    return read_native_scanlines(subimage, miplevel, y, y + 1, z, data);
  }

  bool read_native_scanlines(int subimage, int miplevel, int ybegin, int yend, int /*z*/, void* data) override {
    if (!open_ || subimage != 0 || miplevel != 0 || ybegin < m_spec.y || yend > m_spec.y + m_spec.height ||
        ybegin > yend) {
      errorfmt("mcrecon: no scanlines {}-{} in subimage {} MIP level {}", ybegin, yend, subimage, miplevel);
      return false;
    }
    if (!deferred_error_.empty()) {
      errorfmt("{}", deferred_error_);
      return false;
    }
    if (!ensure_result()) return false;
    if (!result_->notes.empty()) m_spec.attribute("mcreconNotes", result_->notes);  // the run's notes too
    if (!result_->chosen.empty()) m_spec.attribute("mcreconChosen", result_->chosen);
    const std::size_t row = std::size_t(m_spec.width) * 4;
    std::memcpy(data, result_->rgba.data() + std::size_t(ybegin - m_spec.y) * row,
                std::size_t(yend - ybegin) * row * sizeof(float));
    return true;
  }

  bool read_native_scanlines(int subimage, int miplevel, int ybegin, int yend, int z, int chbegin, int chend,
                             void* data) override {
    if (chbegin == 0 && chend == 4) return read_native_scanlines(subimage, miplevel, ybegin, yend, z, data);
    std::vector<float> all(std::size_t(m_spec.width) * 4 * std::size_t(std::max(yend - ybegin, 0)));
    if (!read_native_scanlines(subimage, miplevel, ybegin, yend, z, all.data())) return false;
    const int nc = chend - chbegin;
    float* out = static_cast<float*>(data);
    for (std::size_t p = 0; p < all.size() / 4; ++p)
      for (int c = 0; c < nc; ++c) out[p * nc + c] = all[p * 4 + chbegin + c];
    return true;
  }

 private:
  // The filter runs here, on the first pixel read, once per input and settings.
  bool ensure_result() {
    if (result_) return true;
    if ((result_ = cached_result(key_))) return true;
    try {
      std::lock_guard<std::mutex> run(g_run_mutex);
      if ((result_ = cached_result(key_))) return true;  // another reader was faster
      mcr::Frame frame = mcr::read_frame(request_.source, request_.read);
      if (frame.width != m_spec.width || frame.height != m_spec.height)
        throw mcr::Error(Errc::ReadFailed, "'" + request_.source + "' changed while it was read");
      Filtered filtered = run_filter(request_, settings_, request_.source, frame);
      mcr::put_alpha(frame, std::move(filtered.alpha));
      auto r = std::make_shared<Result>();
      r->notes = filtered.notes;
      r->chosen = filtered.chosen;
      r->width = frame.width;
      r->height = frame.height;
      r->rgba = std::move(mcr::rgba_result(filtered.rgb, frame).storage());  // as write_result writes it
      result_ = r;
      cache_result(key_, std::move(r));
      return true;
    } catch (const std::exception& e) {
      report(*this, e);
      return false;
    }
  }

  // Width and height of the source, from its header only (no pixels). The header
  // must fit what the file can hold (input_limits.h): oiiotool allocates the spec
  // we return before it asks for a pixel.
  static ImageSpec source_header(const std::string& source) {
    auto in = mcr::open_image(source);  // the checks before open(), then its extension's reader only
    mcr::check_header_fits(*in, source);
    return in->spec();
  }

  mp::Request request_;
  std::string settings_, key_, deferred_error_;
  bool open_ = false;
  std::shared_ptr<const Result> result_;
};

// ---------------------------------------------------------------------------

class McreconOutput final : public ImageOutput {
 public:
  ~McreconOutput() override { close(); }
  const char* format_name() const override { return mp::kFormat; }
  int supports(string_view feature) const override {
    // origin/displaywindow: the EXR we write keeps data and display windows, so a
    // crop is not padded out to its display window on the way in.
    return feature == "nchannels" || feature == "alpha" || feature == "random_access" ||
           feature == "arbitrary_metadata" || feature == "origin" || feature == "negativeorigin" ||
           feature == "displaywindow";
  }

  bool open(const std::string& name, const ImageSpec& spec, OpenMode mode = Create) override {
    close();
    if (mode != Create) {
      errorfmt("mcrecon: error: the mcrecon output writes one image (no subimages or MIP levels)");
      return false;
    }
    try {
      request_ = mp::make_request(name, plugin_attributes(spec), true);
      params_text_ = mp::make_reconstruction(request_)->parameters_text();
      settings_ = mp::settings_key(request_, params_text_);
      if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1)
        throw mcr::Error(Errc::InvalidArgument, "mcrecon output '" + name + "': needs a flat 2D image");
      if (spec.deep) throw mcr::Error(Errc::InvalidArgument, "mcrecon output '" + name + "': deep images are not supported");
      m_spec = spec;
      m_spec.set_format(TypeFloat);
      m_spec.channelformats.clear();
      name_ = name;
      shown_name_ = mp::strip_oiiotool_temp(name);
      // oiiotool renames its temp over the name the user gave: that one must be a
      // regular file or a new path too (never a device node, FIFO or directory).
      mcr::check_output_path(shown_name_, {});
      if (name_ != shown_name_) mcr::check_output_target(name_);
      pixels_.assign(std::size_t(spec.width) * spec.height * spec.nchannels, 0.0f);
      rows_.assign(std::size_t(spec.height), false);
      rows_left_ = spec.height;
      open_ = true;
      return true;
    } catch (const std::exception& e) {
      report(*this, e);
      return false;
    }
  }

  bool write_scanline(int y, int z, TypeDesc format, const void* data, stride_t xstride) override {
    if (!open_) {
      errorfmt("mcrecon: error: write_scanline without open");
      return false;
    }
    const int row = y - m_spec.y;
    if (z != 0 || row < 0 || row >= m_spec.height) {
      errorfmt("mcrecon: error: scanline {} is outside the image", y);
      return false;
    }
    data = to_native_scanline(format, data, xstride, scratch_);
    const std::size_t n = std::size_t(m_spec.width) * m_spec.nchannels;
    std::memcpy(pixels_.data() + std::size_t(row) * n, data, n * sizeof(float));
    if (!rows_[std::size_t(row)]) {
      rows_[std::size_t(row)] = true;
      if (--rows_left_ == 0) return filter_and_write();  // all pixels are here
    }
    return true;
  }

  bool close() override {
    if (!open_) return true;
    open_ = false;
    const bool complete = rows_left_ == 0;
    const int missing = rows_left_;
    pixels_.clear();
    pixels_.shrink_to_fit();
    if (!complete) {
      errorfmt("mcrecon: error: '{}' closed with {} scanlines not written: nothing filtered", name_, missing);
      return false;
    }
    return ok_;
  }

 private:
  bool filter_and_write() {
    try {
      std::lock_guard<std::mutex> run(g_run_mutex);
      std::vector<std::string> names(m_spec.channelnames.begin(), m_spec.channelnames.end());
      mcr::Frame frame = mcr::frame_from_channels(shown_name_, m_spec.width, m_spec.height, names,
                                                  std::move(pixels_), request_.read);
      frame.window = mcr::window_of(m_spec);
      Filtered filtered = run_filter(request_, settings_, shown_name_, frame);
      mcr::put_alpha(frame, std::move(filtered.alpha));  // what write_result writes as A
      mcr::WriteOptions wo;
      wo.keep_passes = request_.keep_passes;
      wo.compression = request_.compression;
      wo.attributes = mcr::run_attributes(request_.filter, params_text_, filtered.chosen, filtered.notes);
      for (const mcr::ComponentImage& c : filtered.components)
        wo.layers.emplace_back(mcr::component_layer_prefix(frame.layer) + c.name, &c.rgb);
      mcr::write_result(name_, filtered.rgb, frame, wo);
      ok_ = true;
    } catch (const std::exception& e) {
      report(*this, e);
      ok_ = false;
    }
    return ok_;
  }

  mp::Request request_;
  std::string name_;        // where to write (oiiotool's temp name, renamed by oiiotool)
  std::string shown_name_;  // the name the user gave: messages and frame numbers
  std::string settings_, params_text_;
  std::vector<float> pixels_;
  std::vector<unsigned char> scratch_;
  std::vector<bool> rows_;
  int rows_left_ = 0;
  bool open_ = false, ok_ = false;
};

}  // namespace

OIIO_PLUGIN_EXPORTS_BEGIN

OIIO_EXPORT int mcrecon_imageio_version = OIIO_PLUGIN_VERSION;
OIIO_EXPORT const char* mcrecon_imageio_library_version() { return "mcrecon 0.1.0"; }
OIIO_EXPORT ImageInput* mcrecon_input_imageio_create() { return new McreconInput; }
OIIO_EXPORT const char* mcrecon_input_extensions[] = {"mcrecon", nullptr};
OIIO_EXPORT ImageOutput* mcrecon_output_imageio_create() { return new McreconOutput; }
OIIO_EXPORT const char* mcrecon_output_extensions[] = {"mcrecon", nullptr};

OIIO_PLUGIN_EXPORTS_END

OIIO_PLUGIN_NAMESPACE_END

#include "io/frame_reader.h"

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>

#include "image/lightfield.h"
#include "io/half_buffers.h"
#include "io/channel_roles.h"
#include "io/exr_scanline_io.h"
#include "io/input_limits.h"
#include "io/native_pixels.h"
#include "io/spec_window.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

namespace fs = std::filesystem;
using namespace OIIO;

namespace {

// All channels of every part (subimage), interleaved: as float, or, for a one-part file whose
// channels are half or float (Blender's half EXRs keep depth, normal, position and motion in
// float), in the file's own types, converted only for the channels a pass takes: half the
// memory traffic of a wide render, and no conversion of the channels no filter reads.
struct RawImage {
  int width = 0, height = 0;
  PixelWindow window;
  std::vector<std::string> names;
  std::vector<float> pixels;
  // The native form, used instead of pixels when not empty: packed pixels laid out as `layout`.
  // Not zeroed when sized (every byte is decoded into it): a 50 MB frame's memset and page
  // faults on one thread would be a tenth of the read.
  struct NoInit : std::allocator<unsigned char> {
    template <class U> struct rebind { using other = NoInit; };
    template <class U> void construct(U* p) noexcept { ::new (static_cast<void*>(p)) U; }
    using std::allocator<unsigned char>::allocator;
  };
  std::vector<unsigned char, NoInit> native;
  NativeLayout layout;
  std::shared_ptr<DeepSamples> deep;
  std::shared_ptr<const LightField> lightfield;
  bool independent_samples = false;  // deep, no alpha, not a light field: the per-sample convention
};

std::shared_ptr<DeepSamples> copy_deep(const DeepData& dd, const ImageSpec& spec) {
  auto deep = std::make_shared<DeepSamples>();
  deep->width = spec.width;
  deep->height = spec.height;
  deep->channel_names.assign(spec.channelnames.begin(), spec.channelnames.end());
  for (const ParamValue& a : spec.extra_attribs)
    if (a.name().string().rfind("mcrecon:", 0) == 0) deep->attributes[a.name().string()] = a.get_string();
  const std::int64_t np = std::int64_t(spec.width) * spec.height;
  deep->offsets.assign(std::size_t(np) + 1, 0);
  for (std::int64_t p = 0; p < np; ++p) deep->offsets[std::size_t(p) + 1] = deep->offsets[std::size_t(p)] + dd.samples(p);
  deep->values.assign(std::size_t(spec.nchannels), std::vector<float>(deep->total_samples()));
  for (int c = 0; c < spec.nchannels; ++c)
    for (std::int64_t p = 0; p < np; ++p)
      for (unsigned s = 0, n = dd.samples(p); s < n; ++s)
        deep->values[std::size_t(c)][deep->offsets[std::size_t(p)] + s] = dd.deep_value(p, c, int(s));
  return deep;
}

std::string part_label(const ImageSpec& spec, int part) {
  const std::string name = spec.get_string_attribute("name");
  return "part " + std::to_string(part) + (name.empty() ? "" : " '" + name + "'");
}

// Deep data comes through the ImageInput that read the header, never an ImageBuf
// on the path: that would go through OpenImageIO's process-wide ImageCache, which
// keeps serving the first file read at a path after the file is rewritten (a
// re-rendered frame read again by the Python module, add-on or plugin).
void read_deep(ImageInput& in, RawImage& raw, const std::string& path) {
  if (!in.seek_subimage(0, 0)) throw Error(Errc::ReadFailed, "cannot read deep pixels of '" + path + "': " + in.geterror());
  ImageBuf deepbuf(in.spec());  // deep spec: empty DeepData, no pixels
  if (!deepbuf.deep() || !in.read_native_deep_image(0, 0, *deepbuf.deepdata()))
    throw Error(Errc::ReadFailed, "cannot read deep pixels of '" + path + "' (truncated or corrupt?): " + in.geterror());
  if (deepbuf.spec().width != raw.width || deepbuf.spec().height != raw.height)
    throw Error(Errc::ReadFailed, "'" + path + "' changed while it was read");
  raw.deep = copy_deep(*deepbuf.deepdata(), deepbuf.spec());
  if (deepbuf.spec().alpha_channel < 0) {
    // No alpha: independent samples (the per-sample convention, README): the flat passes are
    // the mean of each pixel's samples (Alg. 1 of Shirley et al., the 1-pixel box). A light
    // field's samples are weighted by its light or aperture (its unfiltered estimate), after
    // the file has been checked against the light-field convention.
    const DeepSamples& d = *raw.deep;
    const std::size_t nc = d.channel_names.size(), np = std::size_t(raw.width) * std::size_t(raw.height);
    std::vector<float> weight;
    if (is_lightfield(d)) {
      raw.lightfield = std::make_shared<const LightField>(decode_lightfield(d, path));
      const LightField& lf = *raw.lightfield;
      weight.resize(lf.samples());
      for (std::size_t i = 0; i < weight.size(); ++i) weight[i] = lightfield_sample_weight(lf, i);
    }
    raw.independent_samples = !raw.lightfield;
    raw.names = d.channel_names;
    raw.pixels.assign(np * nc, 0.0f);
    for (std::size_t p = 0; p < np; ++p) {
      const std::uint64_t a = d.offsets[p], b = d.offsets[p + 1];
      for (std::size_t c = 0; c < nc; ++c) {
        double sum = 0, n = 0;
        for (std::uint64_t i = a; i < b; ++i)
          if (std::isfinite(d.values[c][i])) {
            const double w = weight.empty() ? 1.0 : double(weight[i]);
            sum += w * d.values[c][i], n += w;
          }
        raw.pixels[p * nc + c] = n > 0 ? float(sum / n) : 0.0f;
      }
    }
    return;
  }
  // Flat passes of a deep file with alpha (compositing layers): front-to-back composite.
  ImageBuf flat = ImageBufAlgo::flatten(deepbuf);
  if (flat.has_error()) throw Error(Errc::ReadFailed, "cannot flatten deep '" + path + "': " + flat.geterror());
  raw.names.assign(flat.spec().channelnames.begin(), flat.spec().channelnames.end());
  raw.pixels.resize(std::size_t(raw.width) * raw.height * flat.nchannels());
  flat.get_pixels(flat.roi(), TypeFloat, raw.pixels.data());
}

// Every part of a multi-part file joins the channel list. A part's channel whose
// name an earlier part already uses gets the part's name as a prefix
// ("normal" part with R,G,B -> normal.R, ...), the OpenEXR multi-part convention.
void read_parts(ImageInput& in, RawImage& raw, const std::string& path) {
  std::vector<std::vector<float>> parts;
  std::vector<int> widths;
  for (int part = 0; in.seek_subimage(part, 0); ++part) {
    const ImageSpec spec = in.spec();  // a copy: the probe below seeks
    if (part > 0) {
      if (spec.deep) continue;  // only part 0 may be deep (read as the per-sample buffer)
      if (spec.width != raw.width || spec.height != raw.height || spec.x != raw.window.x || spec.y != raw.window.y)
        throw Error(Errc::SizeMismatch, "'" + path + "' " + part_label(spec, part) + " has data window " +
                                            std::to_string(spec.width) + "x" + std::to_string(spec.height) + " at (" +
                                            std::to_string(spec.x) + "," + std::to_string(spec.y) + "), part 0 " +
                                            std::to_string(raw.width) + "x" + std::to_string(raw.height) + " at (" +
                                            std::to_string(raw.window.x) + "," + std::to_string(raw.window.y) + ")");
    }
    const std::string part_name = spec.get_string_attribute("name");
    for (const auto& n : spec.channelnames) {
      const bool taken = std::find(raw.names.begin(), raw.names.end(), n) != raw.names.end();
      if (taken && part_name.empty())
        throw Error(Errc::ReadFailed, "'" + path + "' " + part_label(spec, part) + " repeats channel '" + n +
                                          "' and has no part name to tell it apart");
      raw.names.push_back(taken ? part_name + "." + n : n);
    }
    bool only_part = false;
    if (part == 0 && native_layout_of(spec, raw.layout)) {
      only_part = !in.seek_subimage(1, 0);
      if (only_part) (void)in.geterror();  // the probe's "no such part" is not this read's error
      if (!in.seek_subimage(0, 0))
        throw Error(Errc::ReadFailed, "cannot read '" + path + "' part 0 again: " + in.geterror());
    }
    if (only_part) {
      raw.native.resize(std::size_t(spec.width) * spec.height * raw.layout.stride);
      if (read_exr_scanlines(path, spec.width, spec.height, raw.layout, raw.native.data())) return;
      if (!in.read_image(0, 0, 0, spec.nchannels, TypeUnknown, raw.native.data()))
        throw Error(Errc::ReadFailed, "cannot read pixels of '" + path + "' " + part_label(spec, part) +
                                          " (truncated or corrupt?): " + in.geterror());
      return;
    }
    parts.emplace_back(std::size_t(spec.width) * spec.height * spec.nchannels);
    widths.push_back(spec.nchannels);
    if (!in.read_image(part, 0, 0, spec.nchannels, TypeFloat, parts.back().data()))
      throw Error(Errc::ReadFailed, "cannot read pixels of '" + path + "' " + part_label(spec, part) +
                                        " (truncated or corrupt?): " + in.geterror());
  }
  if (parts.size() == 1) {
    raw.pixels = std::move(parts.front());
    return;
  }
  const std::size_t n = std::size_t(raw.width) * raw.height, total = raw.names.size();
  raw.pixels.resize(n * total);
  std::size_t first = 0;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const std::size_t nc = std::size_t(widths[k]);
    for (std::size_t i = 0; i < n; ++i)
      std::copy_n(parts[k].data() + i * nc, nc, raw.pixels.data() + i * total + first);
    first += nc;
  }
}

// The file opened, after the checks every read needs: a regular file (a FIFO would block the
// open), header sizes OpenEXR may allocate, then the header against what the file can hold.
std::unique_ptr<ImageInput> open_checked(const std::string& path, InputBudget& budget) {
  auto in = open_image(path);
  budget = check_header_fits(*in, path);
  return in;
}

RawImage read_raw(const std::string& path) {
  InputBudget budget;
  auto in = open_checked(path, budget);
  const ImageSpec spec = in->spec();
  RawImage raw;
  raw.width = spec.width;
  raw.height = spec.height;
  raw.window = window_of(spec);
  try {
    if (spec.deep) {
      check_deep_samples(path, spec.nchannels, budget);
      check_deep_chunk_sizes(path);
      read_deep(*in, raw, path);
    } else {
      read_parts(*in, raw, path);
    }
  } catch (const std::bad_alloc&) {
    throw Error(Errc::ReadFailed, "cannot read '" + path + "': out of memory");
  }
  return raw;
}

// A pass's name, role and channels, its image sized but not yet filled (fill_passes).
Pass pass_shell(const RawImage& raw, const std::string& path, const std::string& group_name, const RoleMatch& m) {
  Pass p;
  p.role = m.role;
  p.name = group_name;
  p.source = path;
  p.space = m.space;
  p.priority = m.priority;
  for (int i : m.indices) p.channels.push_back(raw.names[std::size_t(i)]);
  p.image = Image(raw.width, raw.height, int(m.indices.size()));
  return p;
}

// Fills passes[k] with the raw channels indices[k], all passes in one sweep over the rows: a
// strided gather out of a wide file (28 channels, 720p) is memory-bound, and a row stays in
// cache while every pass takes its channels from it.
void fill_passes(const RawImage& raw, const std::vector<Pass*>& passes, const std::vector<const std::vector<int>*>& indices) {
  const std::size_t w = std::size_t(raw.width);
  const std::size_t nin = raw.names.size();
  parallel_rows(0, raw.height, 0, [&](int y) {
    const std::size_t row = std::size_t(y) * w;
    for (std::size_t k = 0; k < passes.size(); ++k) {
      const std::vector<int>& from = *indices[k];
      const std::size_t nc = from.size();
      float* out = passes[k]->image.data() + row * nc;
      for (std::size_t c = 0; c < nc; ++c) {  // a channel at a time, its type known outside the loop
        const std::size_t ch = std::size_t(from[c]);
        if (raw.native.empty()) {
          const float* in = raw.pixels.data() + row * nin + ch;
          for (std::size_t x = 0; x < w; ++x) out[x * nc + c] = in[x * nin];
          continue;
        }
        const NativeLayout& l = raw.layout;
        native_channel_to_float(raw.native.data() + row * l.stride + l.offset[ch], l.stride, l.is_half[ch], w, out + c, nc);
      }
    }
  });
}

Pass make_pass(const RawImage& raw, const std::string& path, const std::string& group_name, const RoleMatch& m) {
  Pass p = pass_shell(raw, path, group_name, m);
  fill_passes(raw, {&p}, {&m.indices});
  return p;
}

Pass group_as_pass(const RawImage& raw, const std::string& path, const ChannelGroup& g) {
  RoleMatch all{Role::Colour, Space::None, 0, g.indices};
  return make_pass(raw, path, g.name(), all);
}

std::string choose_layer(const std::vector<ChannelGroup>& groups, const std::vector<std::string>& layers,
                         const std::string& wanted, const std::string& path) {
  if (!wanted.empty()) {
    if (std::find(layers.begin(), layers.end(), wanted) != layers.end()) return wanted;
    std::string list;
    for (const auto& l : layers) list += (list.empty() ? "" : ", ") + (l.empty() ? std::string("(none)") : l);
    throw Error(Errc::MissingPass, "no layer '" + wanted + "' in '" + path + "' (layers: " + list + ")");
  }
  // The first view layer with a colour pass; the compositor's output is not a
  // view layer. A named layer without colour still wins over the top level (an
  // mcrecon output keeps R,G,B on top and the view layer's features below).
  for (const ChannelGroup& g : groups) {
    if (g.layer.empty() || g.layer == "Composite") continue;
    for (const RoleMatch& m : classify_group(g))
      if (m.role == Role::Colour) return g.layer;
  }
  for (const auto& l : layers)
    if (!l.empty() && l != "Composite") return l;
  return layers.empty() ? "" : layers.front();
}

Pass resolve_override(const RawImage& raw, const std::vector<ChannelGroup>& groups, const std::string& layer,
                      const std::string& path, const PassOverride& o) {
  for (const ChannelGroup& g : groups) {
    if (g.name() != o.value && !(g.layer == layer && g.pass == o.value)) continue;
    if (auto m = force_role(g, o.role)) return make_pass(raw, path, g.name(), *m);
    throw Error(Errc::MissingPass, "--pass " + std::string(role_name(o.role)) + "=" + o.value + ": channel group '" +
                                       g.name() + "' in '" + path + "' has too few channels for " + role_name(o.role));
  }
  std::error_code ec;
  if (fs::exists(o.value, ec)) return read_pass_file(o.value, o.role);
  throw Error(Errc::MissingPass, "--pass " + std::string(role_name(o.role)) + "=" + o.value + ": no file '" + o.value +
                                     "' and no channel group '" + o.value + "' in '" + path + "'");
}

}  // namespace

std::vector<std::string> loose_pass_files(const ReadOptions& options) {
  std::vector<std::string> files;
  for (const PassOverride& o : options.overrides) {
    std::error_code ec;
    if (fs::is_regular_file(o.value, ec)) files.push_back(o.value);
  }
  if (!options.second_half.empty()) files.push_back(options.second_half);
  return files;
}

PassOverride parse_pass_override(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw Error(Errc::InvalidArgument, "--pass expects ROLE=FILE or ROLE=CHANNEL_GROUP, got '" + text + "'");
  const std::string role = text.substr(0, eq);
  auto r = role_from_name(role);
  if (!r) {
    std::string list;
    for (Role x : kAllRoles) list += (list.empty() ? "" : ", ") + std::string(role_name(x));
    throw Error(Errc::InvalidArgument, "--pass: unknown role '" + role + "' (roles: " + list + ")");
  }
  return {*r, text.substr(eq + 1)};
}

Pass read_pass_file(const std::string& path, Role role) {
  RawImage raw = read_raw(path);
  const auto groups = group_channels(raw.names);
  for (const ChannelGroup& g : groups)  // a pass of that role by name
    for (const RoleMatch& m : classify_group(g))
      if (m.role == role) return make_pass(raw, path, g.name(), m);
  for (const ChannelGroup& g : groups)  // else the first group wide enough
    if (auto m = force_role(g, role)) return make_pass(raw, path, g.name(), *m);
  throw Error(Errc::MissingPass, "'" + path + "' has no channels usable as the " + role_name(role) + " pass");
}

namespace {

Frame frame_from_raw(const RawImage& raw, const std::string& path, const ReadOptions& options) {
  Frame frame;
  frame.width = raw.width;
  frame.height = raw.height;
  frame.path = path;
  frame.window = raw.window;
  frame.deep = raw.deep;
  frame.lightfield = raw.lightfield;

  const auto groups = group_channels(raw.names);
  for (const ChannelGroup& g : groups)
    if (std::find(frame.layers.begin(), frame.layers.end(), g.layer) == frame.layers.end()) frame.layers.push_back(g.layer);
  frame.layer = choose_layer(groups, frame.layers, options.layer, path);

  // Passes of the chosen layer, then top-level channels for roles still missing
  // (an mcrecon output keeps R,G,B on top and the view layer's features below).
  // Then the compositor's output, so a file whose only Combined is Composite's still has a colour pass.
  std::vector<std::string> search = {frame.layer};
  if (!frame.layer.empty()) search.push_back("");
  if (frame.layer != "Composite") search.push_back("Composite");
  std::vector<std::vector<int>> taken;  // each pass's raw channels, filled below in one sweep
  for (const std::string& layer : search) {
    std::set<Role> had;
    for (const Pass& p : frame.passes) had.insert(p.role);
    for (const ChannelGroup& g : groups) {
      if (g.layer != layer) continue;
      for (const RoleMatch& m : classify_group(g)) {
        if (layer != frame.layer && had.count(m.role)) continue;
        frame.passes.push_back(pass_shell(raw, path, g.name(), m));
        taken.push_back(m.indices);
      }
    }
  }
  {
    std::vector<Pass*> passes;
    std::vector<const std::vector<int>*> indices;
    for (std::size_t k = 0; k < taken.size(); ++k) passes.push_back(&frame.passes[k]), indices.push_back(&taken[k]);
    fill_passes(raw, passes, indices);
  }
  for (const PassOverride& o : options.overrides) {
    Pass p = resolve_override(raw, groups, frame.layer, path, o);
    frame.put(std::move(p));
  }
  if (options.keep_extra) {
    // Channels of the passes finally in use; candidates an override replaced are extra.
    std::set<std::string> used;
    for (const Pass& p : frame.passes)
      if (p.source == path) used.insert(p.channels.begin(), p.channels.end());
    for (const ChannelGroup& g : groups) {
      ChannelGroup rest = g;
      rest.indices.clear();
      rest.suffixes.clear();
      for (std::size_t i = 0; i < g.indices.size(); ++i)
        if (!used.count(raw.names[std::size_t(g.indices[i])])) { rest.indices.push_back(g.indices[i]); rest.suffixes.push_back(g.suffixes[i]); }
      if (!rest.indices.empty()) frame.extra.push_back(group_as_pass(raw, path, rest));
    }
  }
  if (options.require_colour && !frame.has(Role::Colour)) {
    std::string list;
    for (const ChannelGroup& g : groups) list += (list.empty() ? "" : ", ") + (g.name().empty() ? std::string("(bare)") : g.name());
    throw Error(Errc::MissingPass, "no colour pass in '" + path + "'" +
                                       (frame.layer.empty() ? "" : " layer '" + frame.layer + "'") +
                                       " (channel groups: " + list + "); name one with --pass colour=GROUP");
  }
  // Independent samples carry their own noise estimate: the variance of each pixel's mean
  // from the two halves of its samples (io/half_buffers.h), unless the file has a variance.
  if (raw.independent_samples && frame.has(Role::Colour) && !frame.has(Role::Variance))
    if (auto v = sample_halves_variance(*raw.deep, frame.get(Role::Colour))) frame.put(std::move(*v));
  frame.check_sizes();
  return frame;
}

}  // namespace

void check_image_file(const std::string& path) {
  InputBudget budget;
  open_checked(path, budget);
}

Frame read_frame(const std::string& path, const ReadOptions& options) {
  if (!options.second_half.empty()) {
    std::error_code ec;
    if (std::filesystem::equivalent(options.second_half, path, ec))
      throw Error(Errc::InvalidArgument, "the second half buffer '" + options.second_half + "' is the input '" + path +
                                             "' itself: give the other half buffer");
    ReadOptions one = options;
    one.second_half.clear();
    return combine_halves(frame_from_raw(read_raw(path), path, one), read_frame(options.second_half, one));
  }
  return frame_from_raw(read_raw(path), path, options);
}

Frame frame_from_channels(const std::string& path, int width, int height, const std::vector<std::string>& channel_names,
                          std::vector<float> pixels, const ReadOptions& options) {
  const std::size_t expected = std::size_t(std::max(width, 0)) * std::size_t(std::max(height, 0)) * channel_names.size();
  if (width <= 0 || height <= 0 || channel_names.empty() || pixels.size() != expected)
    throw Error(Errc::Internal, "frame_from_channels: " + std::to_string(pixels.size()) + " values for " +
                                    std::to_string(width) + "x" + std::to_string(height) + "x" +
                                    std::to_string(channel_names.size()) + " channels of '" + path + "'");
  RawImage raw;
  raw.width = width;
  raw.height = height;
  raw.names = channel_names;
  raw.pixels = std::move(pixels);
  return frame_from_raw(raw, path, options);
}

}  // namespace mcr

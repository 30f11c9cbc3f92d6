// mcrecon: the Python module (pybind11) over the core. Everything it shows of a
// filter comes from the filter's one parameter table; every mcr::Error becomes
// mcrecon.Error here, once (message + .kind). The GIL is released while filtering.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "report_binding.h"
#include "io/deep_writer.h"
#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "io/output_guard.h"
#include "io/sequence.h"
#include "pipeline/alpha_stage.h"
#include "pipeline/sequence_plan.h"
#include "pipeline/denoise_session.h"
#include "pipeline/filter_catalog.h"
#include "util/error.h"
#include "util/thread_count.h"

namespace py = pybind11;

namespace {

using mcr::Errc;
using mcr::Role;
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
using KeyValues = std::vector<std::pair<std::string, std::string>>;

PyObject* g_error_type = nullptr;  // mcrecon.Error

// ------------------------------------------------------------------ tables -> Python

py::object value_to_py(const mcr::ParamValue& v) {
  return std::visit([](const auto& x) -> py::object { return py::cast(x); }, v);
}

py::dict spec_to_dict(const mcr::ParamSpec& s) {
  py::dict d;
  d["name"] = s.name;
  d["type"] = mcr::param_type_name(s.type);
  d["default"] = value_to_py(s.default_value);
  d["help"] = s.help;
  if (s.type == mcr::ParamType::Int) {
    d["min"] = std::int64_t(s.min);
    d["max"] = std::int64_t(s.max);
  }
  if (s.type == mcr::ParamType::Float) {
    d["min"] = s.min;
    d["max"] = s.max;
  }
  if (s.type == mcr::ParamType::Enum) d["choices"] = s.choices;
  return d;
}

py::dict info_to_dict(const mcr::FilterInfo& info) {
  py::list params, req, opt;
  for (const auto& s : info.params) params.append(spec_to_dict(s));
  for (Role r : info.required) req.append(mcr::role_name(r));
  for (Role r : info.optional) opt.append(mcr::role_name(r));
  py::dict d;
  d["name"] = info.name;
  d["summary"] = info.summary;
  d["reference"] = info.reference;
  d["temporal"] = info.temporal;
  d["input"] = info.deep_input ? "deep" : "image";
  d["lightfield"] = info.lightfield_input;
  d["required_passes"] = req;
  d["optional_passes"] = opt;
  d["nonfinite_policy"] = info.nonfinite_policy;
  d["parameters"] = params;
  return d;
}

// ------------------------------------------------------------------ Python -> core

// Parameter values travel as text and are parsed by the table (set_text), so the
// same rules hold as for `mcrecon denoise --set`.
std::string py_to_text(const std::string& key, const py::handle& v) {
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  // Ints as their decimal text, any size: the table then reports an out-of-range value
  // (a cast to long long would fail with a bare RuntimeError beyond 2^63).
  if (py::isinstance<py::int_>(v)) return py::str(v).cast<std::string>();
  if (py::isinstance<py::float_>(v)) return py::str(py::repr(v)).cast<std::string>();  // round-trips
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  if (py::hasattr(v, "dtype") && py::str(v.attr("dtype")).cast<std::string>() == "bool")  // numpy.bool_
    return py::bool_(py::reinterpret_borrow<py::object>(v)).cast<bool>() ? "true" : "false";
  if (py::hasattr(v, "__index__")) return py::str(py::int_(py::reinterpret_borrow<py::object>(v))).cast<std::string>();  // numpy ints
  if (py::hasattr(v, "__float__"))  // numpy floats
    return py::str(py::repr(py::float_(py::reinterpret_borrow<py::object>(v)))).cast<std::string>();
  throw mcr::Error(Errc::BadParameterValue, "parameter '" + key + "': expected bool, int, float or str, got " +
                                                py::str(py::type::handle_of(v).attr("__name__")).cast<std::string>());
}

KeyValues params_from_dict(const py::dict& params) {
  KeyValues kv;
  for (const auto& item : params) {
    const std::string key = py::str(item.first).cast<std::string>();
    kv.emplace_back(key, py_to_text(key, item.second));
  }
  return kv;
}

// accumulate=: True/False (numpy.bool_ too), or the ints 0 and 1; anything else is an
// error naming the setting and what was given.
bool switch_from_py(const char* name, const py::handle& v) {
  const bool is_bool = py::isinstance<py::bool_>(v) ||
                       (py::hasattr(v, "dtype") && py::str(v.attr("dtype")).cast<std::string>() == "bool");
  if (is_bool) return py::bool_(py::reinterpret_borrow<py::object>(v)).cast<bool>();
  if (py::isinstance<py::int_>(v)) {
    const long long i = v.cast<long long>();
    if (i == 0 || i == 1) return i == 1;
  }
  throw mcr::Error(Errc::InvalidArgument, std::string(name) + " expects True or False, got " +
                                              py::repr(v).cast<std::string>());
}

std::vector<mcr::PassOverride> overrides_from_dict(const py::dict& passes) {
  std::vector<mcr::PassOverride> out;
  for (const auto& item : passes) {
    const std::string role = py::str(item.first).cast<std::string>();
    const std::string value = py::str(item.second).cast<std::string>();
    out.push_back(mcr::parse_pass_override(role + "=" + value));
  }
  return out;
}

// display= of the file functions: None, or a dict of the view a PNG/JPEG/TIFF output goes
// through ({'view': 'Filmic', 'look': ..., 'display': 'sRGB', 'exposure': 0.0, 'gamma': 1.0,
// 'config': path, 'bit_depth': 8 or 16}); an unknown key or a value of the wrong type is an
// error naming it and what was given.
mcr::WriteOptions write_options(bool keep_passes, bool keep_components, const py::object& display) {
  mcr::WriteOptions wo;
  wo.keep_passes = keep_passes;
  wo.keep_components = keep_components;  // each denoised light component as a layer (components=light_passes)
  if (display.is_none()) return wo;
  if (!py::isinstance<py::dict>(display))
    throw mcr::Error(Errc::InvalidArgument, "display expects a dict such as {'view': 'Filmic'}, got " +
                                                py::repr(display).cast<std::string>());
  auto bad = [](const std::string& key, const char* what, const py::handle& v) {
    return mcr::Error(Errc::InvalidArgument, "display['" + key + "'] expects " + what + ", got " +
                                                 py::repr(v).cast<std::string>());
  };
  for (const auto& item : py::reinterpret_borrow<py::dict>(display)) {
    const std::string key = py::str(item.first).cast<std::string>();
    const py::handle v = item.second;
    std::string* text = key == "view"      ? &wo.display.view
                        : key == "look"    ? &wo.display.look
                        : key == "display" ? &wo.display.display
                        : key == "config"  ? &wo.display.config
                                           : nullptr;
    if (text) {
      if (!py::isinstance<py::str>(v)) throw bad(key, "a string", v);
      *text = v.cast<std::string>();
    } else if (key == "exposure" || key == "gamma") {
      if (py::isinstance<py::bool_>(v) || !(py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v)))
        throw bad(key, "a number", v);
      (key == "exposure" ? wo.display.exposure : wo.display.gamma) = v.cast<double>();
    } else if (key == "bit_depth") {
      if (py::isinstance<py::bool_>(v) || !py::isinstance<py::int_>(v)) throw bad(key, "8 or 16", v);
      const long long b = v.cast<long long>();
      if (b != 8 && b != 16) throw bad(key, "8 or 16", v);
      wo.bits = int(b);
    } else {
      throw mcr::Error(Errc::InvalidArgument, "display: unknown key '" + key +
                                                  "' (view, look, display, exposure, gamma, config, bit_depth)");
    }
  }
  return wo;
}

mcr::ReadOptions read_options(const std::optional<std::string>& layer, const py::dict& passes) {
  mcr::ReadOptions ro;
  if (layer) ro.layer = *layer;
  ro.overrides = overrides_from_dict(passes);
  return ro;
}

// One numpy pass (H x W or H x W x C) into the frame; checks size and channels.
void add_array(mcr::Frame& frame, Role role, const py::object& obj, mcr::Space space) {
  if (obj.is_none()) return;
  // Its own dtype first: only real numbers are cast to float32 (float64, float16, ints,
  // bools); a complex, object or string array would be cast by dropping or guessing.
  const py::array given = py::array::ensure(obj);
  if (!given) throw mcr::Error(Errc::InvalidArgument, std::string(mcr::role_name(role)) + ": expected a float array, got " +
                                                          py::str(py::type::handle_of(obj).attr("__name__")).cast<std::string>());
  const char kind = given.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b')
    throw mcr::Error(Errc::InvalidArgument, std::string(mcr::role_name(role)) + ": expected a real float array, got " +
                                                py::str(given.dtype().attr("name")).cast<std::string>());
  FloatArray a = FloatArray::ensure(given);
  if (!a) throw mcr::Error(Errc::InvalidArgument, std::string(mcr::role_name(role)) + ": expected a float array");
  if (a.ndim() != 2 && a.ndim() != 3)
    throw mcr::Error(Errc::InvalidArgument, std::string(mcr::role_name(role)) + ": expected an H x W x C array, got " +
                                                std::to_string(a.ndim()) + " dimensions");
  const int h = int(a.shape(0)), w = int(a.shape(1)), c = a.ndim() == 3 ? int(a.shape(2)) : 1;
  if (h <= 0 || w <= 0 || c <= 0) throw mcr::Error(Errc::InvalidArgument, std::string(mcr::role_name(role)) + ": empty array");
  if (frame.passes.empty()) {
    frame.width = w;
    frame.height = h;
  } else if (w != frame.width || h != frame.height) {
    throw mcr::Error(Errc::SizeMismatch, std::string(mcr::role_name(role)) + " pass is " + std::to_string(w) + "x" +
                                             std::to_string(h) + ", colour is " + std::to_string(frame.width) + "x" +
                                             std::to_string(frame.height));
  }
  const int need = mcr::role_channels(role);
  if (c < need)
    throw mcr::Error(Errc::MissingPass, std::string(mcr::role_name(role)) + " pass has " + std::to_string(c) +
                                            " channel(s), needs " + std::to_string(need));
  mcr::Pass p;
  p.role = role;
  p.name = mcr::role_name(role);
  p.source = frame.path;
  p.space = space;
  static const char* xyzw[] = {"X", "Y", "Z", "W"};
  static const char* rgba[] = {"R", "G", "B", "A"};
  for (int i = 0; i < c; ++i)
    p.channels.push_back(p.name + "." + (i < 4 ? (role == Role::Colour || role == Role::Albedo ? rgba[i] : xyzw[i])
                                              : std::to_string(i)));
  p.image = mcr::Image(w, h, c);
  std::memcpy(p.image.data(), a.data(), sizeof(float) * std::size_t(w) * std::size_t(h) * std::size_t(c));
  frame.passes.push_back(std::move(p));
}

struct ArrayPasses {
  py::object colour, albedo, normal, position, depth, motion, variance, sample_count, alpha;
  std::string normal_space;
  py::object diffuse_colour = py::none(), glossy_colour = py::none();  // Blender's DiffCol / GlossCol (mirrors)
  py::object geometry_normal = py::none();  // Blender's world-space Normal beside a camera-space Denoising Normal
};

mcr::Space space_from(const std::string& s, const char* what) {
  if (s == "world") return mcr::Space::World;
  if (s == "camera") return mcr::Space::Camera;
  if (s == "none") return mcr::Space::None;
  throw mcr::Error(Errc::InvalidArgument, std::string(what) + ": space must be world, camera or none, got '" + s + "'");
}

mcr::Frame frame_from_arrays(const ArrayPasses& a) {
  mcr::Frame f;
  f.path = "<arrays>";
  if (a.colour.is_none()) throw mcr::Error(Errc::MissingPass, "no colour array given");
  add_array(f, Role::Colour, a.colour, mcr::Space::None);
  add_array(f, Role::Albedo, a.albedo, mcr::Space::None);
  add_array(f, Role::Normal, a.normal, space_from(a.normal_space, "normal_space"));
  if (!a.geometry_normal.is_none()) {  // as a Blender file's two normals: geometry reads this one (world space)
    add_array(f, Role::Normal, a.geometry_normal, mcr::Space::World);
    f.passes.back().name = "geometry_normal";
    f.passes.back().priority = -1;  // features read `normal`
  }
  add_array(f, Role::Position, a.position, mcr::Space::World);
  add_array(f, Role::Depth, a.depth, mcr::Space::Camera);
  add_array(f, Role::Motion, a.motion, mcr::Space::None);
  add_array(f, Role::Variance, a.variance, mcr::Space::None);
  add_array(f, Role::SampleCount, a.sample_count, mcr::Space::None);
  add_array(f, Role::Alpha, a.alpha, mcr::Space::None);
  add_array(f, Role::DiffuseColour, a.diffuse_colour, mcr::Space::None);
  add_array(f, Role::GlossyColour, a.glossy_colour, mcr::Space::None);
  f.check_sizes();
  return f;
}

// roi: None or 4 ints (x0, y0, x1, y1), non-negative, x0 < x1 and y0 < y1; whether it
// lies inside the image is the filter's check (Filter::execute).
mcr::Roi roi_from_py(const py::object& roi) {
  const std::string given = py::repr(roi).cast<std::string>();
  const std::string form = ": expects (x0, y0, x1, y1) with 0 <= x0 < x1 and 0 <= y0 < y1";
  std::vector<long long> v;
  const bool sequence = py::isinstance<py::sequence>(roi) && !py::isinstance<py::str>(roi) && !py::isinstance<py::bytes>(roi);
  if (sequence)
    for (const py::handle item : roi) {
      // Python and numpy ints (not bool, not float), within int.
      const bool integer = !py::isinstance<py::bool_>(item) && !py::isinstance<py::float_>(item) &&
                           py::hasattr(item, "__index__");
      if (!integer) {
        v.clear();
        break;
      }
      const py::int_ i(py::reinterpret_borrow<py::object>(item));
      if (i < py::int_(0) || i > py::int_(std::numeric_limits<int>::max()))
        throw mcr::Error(Errc::InvalidArgument, "roi " + given + " has a coordinate outside [0, " +
                                                    std::to_string(std::numeric_limits<int>::max()) + "]" + form);
      v.push_back(i.cast<long long>());
    }
  if (v.size() != 4) throw mcr::Error(Errc::InvalidArgument, "roi " + given + " is not 4 ints" + form);
  if (v[0] >= v[2] || v[1] >= v[3]) throw mcr::Error(Errc::InvalidArgument, "roi " + given + " is empty" + form);
  return {int(v[0]), int(v[1]), int(v[2]), int(v[3])};
}

// A Python (or numpy) int within C++ int; anything else an mcrecon.Error naming the
// argument and repeating what was given (pybind11's own int conversion raises a
// TypeError that does neither).
int int_from_py(const char* name, const py::handle& v) {
  const bool integer = !py::isinstance<py::bool_>(v) && !py::isinstance<py::float_>(v) && py::hasattr(v, "__index__");
  const std::string range = "[" + std::to_string(std::numeric_limits<int>::min()) + ", " +
                            std::to_string(std::numeric_limits<int>::max()) + "]";
  if (integer) {
    const py::int_ i(py::reinterpret_borrow<py::object>(v));
    if (i >= py::int_(std::numeric_limits<int>::min()) && i <= py::int_(std::numeric_limits<int>::max()))
      return i.cast<int>();
  }
  throw mcr::Error(Errc::InvalidArgument, std::string(name) + " expects an int in " + range + ", got " +
                                              py::repr(v).cast<std::string>());
}

mcr::ExecOptions exec_options(int threads, const py::object& roi) {
  mcr::ExecOptions eo;
  eo.nthreads = threads;
  if (!roi.is_none()) eo.roi = roi_from_py(roi);
  return eo;
}

py::array_t<float> to_numpy(mcr::Image img) {
  auto* holder = new mcr::Image(std::move(img));
  py::capsule owner(holder, [](void* p) { delete static_cast<mcr::Image*>(p); });
  const py::ssize_t h = holder->height(), w = holder->width(), c = holder->channels();
  return py::array_t<float>({h, w, c}, {w * c * py::ssize_t(sizeof(float)), c * py::ssize_t(sizeof(float)), py::ssize_t(sizeof(float))},
                            holder->data(), owner);
}

// {"required": [...], "optional": [...], "why": {role: setting}} (why: the required
// passes that a setting needs, e.g. {"albedo": "demodulate"}).
py::dict needs_dict(const mcr::PassNeeds& n) {
  py::list req, opt;
  py::dict why;
  for (std::size_t i = 0; i < n.required.size(); ++i) {
    req.append(mcr::role_name(n.required[i]));
    if (!n.why[i].empty()) why[mcr::role_name(n.required[i])] = n.why[i];
  }
  for (Role r : n.optional) opt.append(mcr::role_name(r));
  py::dict d;
  d["required"] = req;
  d["optional"] = opt;
  d["why"] = why;
  return d;
}

py::dict times_dict(const mcr::StageTimes& t) {
  py::dict d;
  d["read_ms"] = t.read_ms;
  d["filter_ms"] = t.filter_ms;
  d["write_ms"] = t.write_ms;
  d["total_ms"] = t.total_ms();
  return d;
}

// filter auto's choice per stage ({"beauty": "atrous"}, or the light stages'), None for another filter.
py::object choices_dict(const std::vector<mcr::StageChoice>& choices) {
  if (choices.empty()) return py::none();
  py::dict d;
  for (const mcr::StageChoice& c : choices) d[py::str(c.stage)] = c.filter;
  return std::move(d);
}

// ------------------------------------------------------------------ Session

// One reconstruction (optional accumulation stage + a filter committed once), with
// its temporal history kept across calls. Shared by several Python threads, its calls
// run one at a time (mcr::Reconstruction's lock); frame order is the caller's.
class Session {
 public:
  Session(const std::string& filter, const py::dict& params, int threads, const py::handle& accumulate)
      : session_(filter, params_from_dict(params), switch_from_py("accumulate", accumulate)),
        threads_(mcr::checked_thread_count(threads, "threads=" + std::to_string(threads))) {}

  std::string name() { return session_.filter().info().name; }
  bool temporal() { return session_.reconstruction().temporal(); }
  bool accumulates() { return session_.reconstruction().accumulates(); }
  py::dict params() {
    py::dict d;
    for (const auto& kv : session_.filter().params().values()) d[py::str(kv.first)] = value_to_py(kv.second);
    return d;
  }
  py::dict needs() { return needs_dict(session_.reconstruction().needs()); }
  // The reconstruction serialises its calls (a mutex held across run, reset and notes):
  // every call that may wait on it releases the GIL first, so a thread waiting for the
  // session never blocks the one that holds it.
  std::vector<std::string> notes() {
    py::gil_scoped_release release;
    return session_.reconstruction().notes();
  }
  py::object chosen() {
    std::vector<mcr::StageChoice> c;
    {
      py::gil_scoped_release release;
      c = session_.reconstruction().choices();
    }
    return choices_dict(c);
  }
  void reset() {
    py::gil_scoped_release release;
    session_.reconstruction().reset();
  }

  py::array_t<float> denoise(const ArrayPasses& a, const py::object& roi) {
    mcr::Frame frame = frame_from_arrays(a);
    const mcr::ExecOptions eo = exec_options(threads_, roi);
    mcr::Image out, alpha;
    const bool given = frame.has(Role::Alpha);
    {
      py::gil_scoped_release release;
      out = session_.reconstruction().run(frame, eo, nullptr, given ? &alpha : nullptr);
    }
    if (!given) return to_numpy(std::move(out));
    // With an alpha given: R, G, B and the filtered alpha (the given one where it is kept).
    mcr::put_alpha(frame, std::move(alpha));
    return to_numpy(mcr::rgba_result(out, frame));
  }

  py::dict denoise_file(const std::string& input, const std::string& output, const std::optional<std::string>& layer,
                        const py::dict& passes, bool keep_passes, bool keep_components = false,
                        const py::object& display = py::none(), int max_memory_mb = 0,
                        const std::optional<std::string>& half = std::nullopt) {
    mcr::ReadOptions ro = read_options(layer, passes);
    if (half) ro.second_half = *half;
    const mcr::WriteOptions wo = write_options(keep_passes, keep_components, display);
    mcr::ReadOptions r = ro;
    r.keep_extra = keep_passes;
    const mcr::ExecOptions eo = exec_options(threads_, py::none());
    mcr::StageTimes t;
    {
      py::gil_scoped_release release;
      t = max_memory_mb > 0 ? session_.run_in_bands(input, output, r, wo, eo, 0, double(max_memory_mb) * 1024.0 * 1024.0, {})
                            : session_.run(input, output, r, wo, eo);
    }
    py::dict d = times_dict(t);
    // What auto chose and scored, unused settings: mcrecon.denoise_file keeps no Session. In
    // bands: the bands, then every band's notes once.
    if (max_memory_mb > 0) d["notes"] = t.notes;
    else d["notes"] = notes();
    d["chosen"] = choices_dict(t.choices);
    return d;
  }

 private:
  mcr::DenoiseSession session_;
  int threads_;
};

void raise_error(Errc code, const std::string& message) {
  py::object exc = py::reinterpret_borrow<py::object>(g_error_type)(py::str(message));
  exc.attr("kind") = mcr::errc_name(code);
  PyErr_SetObject(g_error_type, exc.ptr());
}

}  // namespace

PYBIND11_MODULE(mcrecon, m) {
  m.doc() = "mcrecon: reconstruct clean images from noisy Monte Carlo renders (filters from the mcrecon core)";
  m.attr("__version__") = MCRECON_VERSION;

  // mcrecon.Error(message) with .kind: "unknown_parameter", "missing_pass", ...
  py::dict error_ns;
  error_ns["kind"] = "internal";
  error_ns["__doc__"] = "An mcrecon error: str(e) is the message (naming the filter, parameter, pass or file), "
                        "e.kind the error kind (unknown_filter, unknown_parameter, parameter_out_of_range, "
                        "bad_parameter_value, missing_pass, size_mismatch, file_not_found, ...).";
  g_error_type = PyErr_NewException("mcrecon.Error", PyExc_RuntimeError, error_ns.ptr());
  if (!g_error_type) throw py::error_already_set();
  m.attr("Error") = py::reinterpret_borrow<py::object>(g_error_type);
  // Every C++ exception leaves as mcrecon.Error, never a bare RuntimeError: a Python error
  // already set (a progress callback's), a TypeError or ValueError pybind11 raises itself,
  // and MemoryError keep their own type.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const mcr::Error& e) {
      raise_error(e.code(), e.what());
    } catch (const py::cast_error& e) {  // a value pybind11 could not convert
      raise_error(Errc::InvalidArgument, std::string("cannot convert a value: ") + e.what());
    } catch (const py::error_already_set&) {
      throw;
    } catch (const py::builtin_exception&) {
      throw;
    } catch (const std::bad_alloc&) {
      throw;
    } catch (const std::exception& e) {
      raise_error(Errc::Internal, e.what());
    }
  });

  m.def("filter_names", &mcr::catalog_names,
        "Names of every filter, in registry order, then auto (which scores them and runs the best).");
  m.def(
      "filters",
      [] {
        py::list out;
        for (const auto& n : mcr::catalog_names()) out.append(info_to_dict(mcr::catalog_info(n)));
        return out;
      },
      "Every filter with its full parameter table (same content as `mcrecon filters --json`).");
  m.def(
      "filter_info", [](const std::string& name) { return info_to_dict(mcr::catalog_info(name)); }, py::arg("name"),
      "One filter's description and parameter table; raises mcrecon.Error for an unknown name.");

  py::class_<Session>(m, "Session",
                      "A committed filter that keeps temporal history across calls (one per shot / animation).")
      .def(py::init<const std::string&, const py::dict&, int, const py::handle&>(), py::arg("filter"),
           py::arg("params") = py::dict(), py::arg("threads") = 0, py::kw_only(), py::arg("accumulate") = false,
           "accumulate=True: the temporal accumulation stage (`mcrecon denoise --accumulate`) before the filter")
      .def_property_readonly("filter", &Session::name)
      .def_property_readonly("temporal", &Session::temporal, "frame order matters (temporal filter or accumulate)")
      .def_property_readonly("accumulate", &Session::accumulates)
      .def_property_readonly("params", &Session::params, "every parameter value (defaults filled in)")
      .def("needs", &Session::needs, "the passes these settings need and use, as mcrecon.needs()")
      .def("notes", &Session::notes,
           "settings given that have no effect, then the notes of the last run (filter, accumulation)")
      .def("chosen", &Session::chosen,
           "filter 'auto': what it ran in the last run, per stage ({'beauty': 'atrous'}, or the light stages' "
           "with components=light_passes; 'input' where it kept the input, 'atrous+pwaf' where it ran the mean of two); "
           "None for another filter")
      .def("reset", &Session::reset, "drop temporal history (new shot)")
      .def(
          "denoise",
          [](Session& s, py::object colour, py::object albedo, py::object normal, py::object position, py::object depth,
             py::object motion, py::object variance, py::object sample_count, py::object alpha,
             const std::string& normal_space, const py::object& roi, py::object diffuse_colour, py::object glossy_colour,
             py::object geometry_normal) {
            return s.denoise({colour, albedo, normal, position, depth, motion, variance, sample_count, alpha, normal_space,
                              diffuse_colour, glossy_colour, geometry_normal},
                             roi);
          },
          py::arg("colour"), py::arg("albedo") = py::none(), py::arg("normal") = py::none(),
          py::arg("position") = py::none(), py::arg("depth") = py::none(), py::arg("motion") = py::none(),
          py::arg("variance") = py::none(), py::arg("sample_count") = py::none(), py::arg("alpha") = py::none(),
          py::arg("normal_space") = "world", py::arg("roi") = py::none(), py::arg("diffuse_colour") = py::none(),
          py::arg("glossy_colour") = py::none(), py::arg("geometry_normal") = py::none(),
          "Filters one frame given as float32 H x W x C arrays; returns H x W x 3 float32, H x W x 4 with alpha "
          "given (the alpha filtered as params alpha= says, else as given). diffuse_colour / "
          "glossy_colour: Blender's Diffuse / Glossy Color passes (bmfr and accumulate tell mirrors by them). "
          "geometry_normal: Blender's world-space Normal pass beside a camera-space normal (its Denoising Normal, "
          "normal_space='camera'), as a file holds both: the alpha's partly covered pixels are read from it.")
      .def("denoise_file", &Session::denoise_file, py::arg("input"), py::arg("output"), py::arg("layer") = py::none(),
           py::arg("passes") = py::dict(), py::arg("keep_passes") = false, py::arg("keep_components") = false,
           py::arg("display") = py::none(), py::arg("max_memory_mb") = 0, py::arg("half") = py::none(),
           "Reads a render (multilayer EXR), filters it and writes output (temp + rename) in the format its "
           "extension names (.exr; .png, .jpg, .tif through the OpenColorIO view in display=, e.g. "
           "{'view': 'Filmic', 'exposure': 0.5}); returns stage timings "
           "and the notes (as notes()). max_memory_mb > 0: the frame in bands of rows under that many MB, "
           "the same pixels (as --max-memory). "
           "passes: {role: channel group or file}, e.g. {'colour': 'Composite.Combined'}. keep_components=True "
           "(with params components='light_passes'): each denoised light component as its own layer, as "
           "--keep-components. half: the other half buffer of the input (the same render's samples split in two, "
           "Blender's sample_offset), as --half: their mean is filtered, with the noise from their difference.");

  m.def(
      "denoise",
      [](const std::string& filter, py::object colour, py::object albedo, py::object normal, py::object position,
         py::object depth, py::object motion, py::object variance, py::object sample_count, py::object alpha,
         const std::string& normal_space, const py::dict& params, int threads, const py::object& roi,
         const py::object& accumulate, py::object diffuse_colour, py::object glossy_colour, py::object geometry_normal) {
        Session s(filter, params, threads, accumulate);
        return s.denoise({colour, albedo, normal, position, depth, motion, variance, sample_count, alpha, normal_space,
                          diffuse_colour, glossy_colour, geometry_normal},
                         roi);
      },
      py::arg("filter"), py::arg("colour"), py::arg("albedo") = py::none(), py::arg("normal") = py::none(),
      py::arg("position") = py::none(), py::arg("depth") = py::none(), py::arg("motion") = py::none(),
      py::arg("variance") = py::none(), py::arg("sample_count") = py::none(), py::arg("alpha") = py::none(),
      py::arg("normal_space") = "world", py::arg("params") = py::dict(), py::arg("threads") = 0,
      py::arg("roi") = py::none(), py::arg("accumulate") = false, py::arg("diffuse_colour") = py::none(),
      py::arg("glossy_colour") = py::none(), py::arg("geometry_normal") = py::none(),
      "Filters one frame given as float32 H x W x C numpy arrays (colour RGB or RGBA, features as available; "
      "diffuse_colour / glossy_colour: Blender's Diffuse / Glossy Color, by which bmfr and accumulate tell mirrors; "
      "geometry_normal: Blender's world-space Normal beside a camera-space normal, normal_space='camera'); "
      "returns H x W x 3 float32, H x W x 4 with alpha given (the alpha filtered as params alpha= says, else as "
      "given).");

  m.def(
      "denoise_file",
      [](const std::string& input, const std::string& output, const std::string& filter, const py::dict& params,
         const std::optional<std::string>& layer, const py::dict& passes, bool keep_passes, int threads,
         const py::object& accumulate, bool keep_components, const py::object& display, int max_memory_mb,
         const std::optional<std::string>& half) {
        Session s(filter, params, threads, accumulate);
        return s.denoise_file(input, output, layer, passes, keep_passes, keep_components, display, max_memory_mb, half);
      },
      py::arg("input"), py::arg("output"), py::arg("filter"), py::arg("params") = py::dict(),
      py::arg("layer") = py::none(), py::arg("passes") = py::dict(), py::arg("keep_passes") = false,
      py::arg("threads") = 0, py::arg("accumulate") = false, py::arg("keep_components") = false,
      py::arg("display") = py::none(), py::arg("max_memory_mb") = 0, py::arg("half") = py::none(),
      "Same as `mcrecon denoise INPUT -o OUTPUT -f FILTER --set k=v ...` (accumulate=True: --accumulate; half=: "
      "--half, the other half buffer; "
      "keep_components=True: --keep-components, with params={'components': 'light_passes'}; display={'view': "
      "'Filmic', 'look': ..., 'exposure': ..., 'gamma': ..., 'bit_depth': 8 or 16}: --view etc. for a "
      ".png/.jpg/.tif output); returns "
      "stage timings, the notes `--verbose` prints (filter='auto': the scores and the filter chosen) and 'chosen' "
      "(Session.chosen()).");

  m.def(
      "denoise_sequence",
      [](const std::string& input, const std::string& output, const py::object& first_arg, const py::object& last_arg,
         const std::string& filter,
         const py::dict& params, const std::optional<std::string>& layer, const py::dict& passes, int threads,
         const std::optional<std::function<void(std::int64_t, std::int64_t, std::string)>>& progress, const py::object& accumulate,
         bool keep_components, const py::object& display, const py::object& warmup_arg) {
        const int first = int_from_py("first", first_arg), last = int_from_py("last", last_arg);
        const int warmup = int_from_py("warmup", warmup_arg);
        if (warmup < 0 || std::size_t(warmup) > mcr::kMaxFrames)
          throw mcr::Error(Errc::InvalidArgument, "warmup " + std::to_string(warmup) + ": give 0 to " +
                                                      std::to_string(mcr::kMaxFrames) + " frames");
        for (const std::string* p : {&input, &output})
          if (!mcr::is_sequence_pattern(*p))
            throw mcr::Error(Errc::InvalidArgument, std::string(p == &input ? "input" : "output") + " '" + *p +
                                                        "' must be a sequence pattern (#### or %04d)");
        const mcr::FrameList frames = mcr::FrameList::span(first, last);
        // Every input, and every output against them all, checked before the first frame is
        // filtered (as the CLI does); 64-bit counters: a range ending at INT_MAX ends.
        std::vector<std::string> inputs;
        for (std::int64_t f = first; f <= last; ++f) {
          inputs.push_back(mcr::sequence_path(input, int(f)));
          std::error_code ec;
          if (!std::filesystem::exists(inputs.back(), ec))
            throw mcr::Error(Errc::FileNotFound, "cannot read '" + inputs.back() + "': no such file");
        }
        for (std::string& f : mcr::loose_pass_files(read_options(layer, passes))) inputs.push_back(std::move(f));
        mcr::check_sequence_outputs(output, frames, inputs);
        Session s(filter, params, threads, accumulate);
        // warmup as --warmup: the frames before `first` the plan reads and does not write.
        std::vector<std::string> warm;
        for (const mcr::FrameJob& j : mcr::plan_sequence(frames, std::vector<bool>(frames.size(), false), s.temporal(), warmup)) {
          if (j.write) break;
          warm.push_back(mcr::sequence_path(input, j.frame));
          std::error_code ec;
          if (!std::filesystem::exists(warm.back(), ec))
            throw mcr::Error(Errc::FileNotFound, "cannot read '" + warm.back() + "' (a warmup frame): no such file");
        }
        if (!warm.empty()) mcr::check_sequence_outputs(output, frames, warm);
        for (const std::string& w : warm) s.denoise_file(w, "", layer, passes, false, false, py::none());
        py::list outputs;
        for (std::int64_t f = first; f <= last; ++f) {
          const std::string out = mcr::sequence_path(output, int(f));
          s.denoise_file(inputs[std::size_t(f - first)], out, layer, passes, false, keep_components, display);
          outputs.append(out);
          if (progress) (*progress)(f - first + 1, std::int64_t(last) - first + 1, out);
        }
        return outputs;
      },
      py::arg("input"), py::arg("output"), py::arg("first"), py::arg("last"), py::arg("filter"),
      py::arg("params") = py::dict(), py::arg("layer") = py::none(), py::arg("passes") = py::dict(),
      py::arg("threads") = 0, py::arg("progress") = py::none(), py::arg("accumulate") = false,
      py::arg("keep_components") = false, py::arg("display") = py::none(), py::arg("warmup") = 0,
      "Denoises frames first..last of a pattern (#### or %04d) in order with one Session (temporal history; "
      "accumulate=True as --accumulate; warmup=N as --warmup: a temporal filter's history starts N frames "
      "before first, read and not written); progress(done, total, output) is called after each frame. Returns "
      "the outputs written.");

  m.def(
      "inactive_parameters",
      [](const std::string& filter, const py::dict& params) {
        // A parameter is inactive when, given explicitly, the filter would call it unused
        // under these settings (Filter::unused_settings: "<name> has no effect ...").
        const auto base = params_from_dict(params);
        const auto probe = mcr::make_committed_filter(filter, base);
        auto has_no_effect = [](const mcr::Filter& f, const std::string& name) {
          for (const std::string& line : f.unused_settings())
            if (line.rfind(name + " has no effect", 0) == 0) return true;
          return false;
        };
        std::vector<std::string> out;
        for (const mcr::ParamSpec& spec : probe->info().params) {
          bool given = false;
          for (const auto& kv : base) given = given || kv.first == spec.name;
          if (given) {
            if (has_no_effect(*probe, spec.name)) out.push_back(spec.name);
            continue;
          }
          auto with = base;
          with.emplace_back(spec.name, mcr::param_value_text(spec.default_value));
          if (has_no_effect(*mcr::make_committed_filter(filter, with), spec.name)) out.push_back(spec.name);
        }
        return out;
      },
      py::arg("filter"), py::arg("params") = py::dict(),
      "The parameters that have no effect under these settings (the foveation set without foveated=true, "
      "a feature's sigma with its weight off, ...), as `mcrecon denoise --verbose` would note them: the "
      "add-on's panel hides them.");

  m.def(
      "check_outputs",
      [](const std::vector<std::string>& outputs, const std::vector<std::string>& inputs) {
        mcr::check_output_paths(outputs, inputs);
        for (const std::string& o : outputs) mcr::check_write(o, mcr::WriteOptions{});
      },
      py::arg("outputs"), py::arg("inputs"),
      "Raises mcrecon.Error unless every output may be written as the CLI would: never an input, never "
      "two outputs one file, only a regular file or a new path, a format its extension names.");

  m.def(
      "convert_file",
      [](const std::string& input, const std::string& output, const py::object& display) {
        const mcr::WriteOptions wo = write_options(false, false, display);
        mcr::check_output_path(output, {input});
        mcr::check_write(output, wo);
        py::gil_scoped_release release;
        mcr::ReadOptions ro;
        const mcr::Frame frame = mcr::read_frame(input, ro);
        mcr::write_result(output, frame.image(mcr::Role::Colour), frame, wo);
      },
      py::arg("input"), py::arg("output"), py::arg("display") = py::none(),
      "Writes the colour (and alpha) of a render or a denoised EXR in the format output's extension names, as "
      "denoise_file writes its result (display= as there): the add-on turns its denoised EXR into the user's PNG.");

  m.def(
      "write_deep",
      [](const std::string& path, const py::dict& channels, const py::dict& attributes) {
        mcr::check_output_path(path, {});
        mcr::DeepSamples d;
        std::vector<py::array_t<float, py::array::c_style | py::array::forcecast>> arrays;
        std::size_t k = 0;
        for (const auto& [key, value] : channels) {
          const std::string name = py::str(key);
          auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
          if (!a || a.ndim() != 3)
            throw mcr::Error(mcr::Errc::InvalidArgument, "write_deep: channel '" + name +
                                                             "' must be an array of shape (samples, height, width)");
          if (arrays.empty()) {
            k = std::size_t(a.shape(0));
            d.height = int(a.shape(1));
            d.width = int(a.shape(2));
          } else if (std::size_t(a.shape(0)) != k || a.shape(1) != d.height || a.shape(2) != d.width) {
            throw mcr::Error(mcr::Errc::SizeMismatch, "write_deep: channel '" + name + "' has another shape than '" +
                                                          d.channel_names.front() + "'");
          }
          d.channel_names.push_back(name);
          arrays.push_back(a);
        }
        if (arrays.empty()) throw mcr::Error(mcr::Errc::InvalidArgument, "write_deep: no channel given");
        for (const auto& [key, value] : attributes) d.attributes[py::str(key)] = py::str(value);
        const std::size_t np = std::size_t(d.width) * std::size_t(d.height);
        d.offsets.resize(np + 1);
        for (std::size_t p = 0; p <= np; ++p) d.offsets[p] = p * k;
        d.values.assign(arrays.size(), std::vector<float>(np * k));
        for (std::size_t c = 0; c < arrays.size(); ++c) {
          const float* src = arrays[c].data();  // [s][y][x] -> pixel-major
          for (std::size_t s = 0; s < k; ++s)
            for (std::size_t p = 0; p < np; ++p) d.values[c][p * k + s] = src[s * np + p];
        }
        py::gil_scoped_release release;
        mcr::write_deep_samples(d, path);
      },
      py::arg("path"), py::arg("channels"), py::arg("attributes") = py::dict(),
      "Writes a deep OpenEXR in the per-sample convention (README): channels {name: float array of shape "
      "(samples, height, width)}, the same number of samples in every pixel, e.g. R, G, B, Z, dx, dy; "
      "attributes {name: value} as header attributes (mcrecon:lens_mm, ...). Temp file + rename.");

  m.def(
      "needs",
      [](const std::string& filter, const py::dict& params, const py::object& accumulate) {
        const mcr::Reconstruction r(mcr::make_committed_filter(filter, params_from_dict(params)),
                                    switch_from_py("accumulate", accumulate));
        return needs_dict(r.needs());
      },
      py::arg("filter"), py::arg("params") = py::dict(), py::arg("accumulate") = false,
      "The passes a filter needs with these settings (and accumulate): {'required': [role, ...], "
      "'optional': [role, ...], 'why': {role: the setting that requires it}}; parameter errors raise "
      "mcrecon.Error as Session does.");

  add_report_binding(m);
}

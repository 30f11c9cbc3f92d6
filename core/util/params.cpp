#include "util/params.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "util/error.h"

namespace mcr {

const char* param_type_name(ParamType t) {
  switch (t) {
    case ParamType::Int: return "int";
    case ParamType::Float: return "float";
    case ParamType::Bool: return "bool";
    case ParamType::Enum: return "enum";
  }
  return "?";
}

ParamSpec ParamSpec::Int(std::string name, std::int64_t def, std::int64_t lo, std::int64_t hi, std::string help) {
  ParamSpec s;
  s.name = std::move(name); s.type = ParamType::Int; s.default_value = def;
  s.min = double(lo); s.max = double(hi); s.help = std::move(help);
  return s;
}
ParamSpec ParamSpec::Float(std::string name, double def, double lo, double hi, std::string help) {
  ParamSpec s;
  s.name = std::move(name); s.type = ParamType::Float; s.default_value = def;
  s.min = lo; s.max = hi; s.help = std::move(help);
  return s;
}
ParamSpec ParamSpec::Bool(std::string name, bool def, std::string help) {
  ParamSpec s;
  s.name = std::move(name); s.type = ParamType::Bool; s.default_value = def; s.help = std::move(help);
  return s;
}
ParamSpec ParamSpec::Enum(std::string name, std::string def, std::vector<std::string> choices, std::string help) {
  ParamSpec s;
  s.name = std::move(name); s.type = ParamType::Enum; s.default_value = std::move(def);
  s.choices = std::move(choices); s.help = std::move(help);
  return s;
}

void report_unused(const ParamSet& params, const std::string& name, const std::string& why,
                   std::vector<std::string>& out) {
  if (params.has(name) && params.was_set(name)) out.push_back(name + " has no effect " + why);
}

std::string number_text(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  // The fewest digits that read back as v, but whole digits up to 6 of them ("10", not
  // "1e+01"; "1e+06" as %g prints it).
  const int whole = v == 0 ? 1 : int(std::floor(std::log10(std::fabs(v)))) + 1;
  char buf[32];
  for (int prec = 1; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", whole >= prec && whole <= 6 ? whole : prec, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string rounded_text(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string param_value_text(const ParamValue& v) {
  if (auto i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (auto d = std::get_if<double>(&v)) return number_text(*d);
  if (auto b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  return std::get<std::string>(v);
}

ParamSet::ParamSet(std::string owner, const ParamTable* table) : owner_(std::move(owner)), table_(table) {
  for (const ParamSpec& s : *table_) values_[s.name] = s.default_value;
}

bool ParamSet::has(const std::string& name) const { return values_.count(name) != 0; }

const ParamSpec& ParamSet::spec(const std::string& name) const {
  if (table_)
    for (const ParamSpec& s : *table_)
      if (s.name == name) return s;
  std::string known;
  if (table_)
    for (const ParamSpec& s : *table_) known += (known.empty() ? "" : ", ") + s.name;
  throw Error(Errc::UnknownParameter, "filter '" + owner_ + "' has no parameter '" + name + "'" +
                                          (known.empty() ? " (it takes none)" : " (known: " + known + ")"));
}

namespace {

// A bound at infinity or at the end of its type is no bound: printed as such, never as
// 300 digits of DBL_MAX.
bool bounded(const ParamSpec& s, double b) {
  if (!std::isfinite(b) || std::fabs(b) == std::numeric_limits<double>::max()) return false;
  return s.type != ParamType::Int || std::fabs(b) < 9.2e18;
}

std::string bound_text(const ParamSpec& s, double b) {
  return s.type == ParamType::Int ? std::to_string(std::int64_t(b)) : number_text(b);
}

// "in [0, 64]", ">= 0 (no upper bound)", "one of: a, b": what a valid value is.
std::string valid_text(const ParamSpec& s) {
  const std::string r = param_range_text(s);
  return r.empty() || r[0] != '[' ? r : "in " + r;
}

std::string prefix(const std::string& owner, const ParamSpec& s) {
  return "parameter '" + s.name + "' of filter '" + owner + "'";
}

// `given` is what the caller gave, as the messages show it: the user's own text quoted
// (set_text), a typed value printed readably (set).
[[noreturn]] void out_of_range(const std::string& owner, const ParamSpec& s, const std::string& given) {
  throw Error(Errc::ParameterOutOfRange, prefix(owner, s) + " must be " + valid_text(s) + ", got " + given);
}

[[noreturn]] void bad_value(const std::string& owner, const ParamSpec& s, const std::string& given) {
  std::string want;
  switch (s.type) {
    case ParamType::Int: want = "an integer " + valid_text(s); break;
    case ParamType::Float: want = "a finite number " + valid_text(s); break;
    case ParamType::Bool: want = "a bool (1, true, on, yes or 0, false, off, no)"; break;
    case ParamType::Enum: want = valid_text(s); break;
  }
  throw Error(Errc::BadParameterValue, prefix(owner, s) + " expects " + want + ", got " + given);
}

std::string quoted(const std::string& text) { return "'" + text + "'"; }

}  // namespace

std::string param_range_text(const ParamSpec& s) {
  switch (s.type) {
    case ParamType::Int:
    case ParamType::Float: {
      const bool lo = bounded(s, s.min), hi = bounded(s, s.max);
      if (lo && hi) return "[" + bound_text(s, s.min) + ", " + bound_text(s, s.max) + "]";
      if (lo) return ">= " + bound_text(s, s.min) + " (no upper bound)";
      if (hi) return "<= " + bound_text(s, s.max) + " (no lower bound)";
      return "any number";
    }
    case ParamType::Bool: return "";
    case ParamType::Enum: {
      std::string r;
      for (const auto& c : s.choices) r += (r.empty() ? "" : ", ") + c;
      return "one of: " + r;
    }
  }
  return "";
}

void ParamSet::set(const std::string& name, const ParamValue& value) {
  // A typed value has no text of its own: printed readably, a string quoted.
  set_checked(name, value,
              std::holds_alternative<std::string>(value) ? quoted(std::get<std::string>(value)) : param_value_text(value));
}

void ParamSet::set_checked(const std::string& name, const ParamValue& value, const std::string& given) {
  const ParamSpec& s = spec(name);
  ParamValue v = value;
  switch (s.type) {
    case ParamType::Int: {
      // Whole numbers only; a huge one is out of range (not a type error) and is never
      // cast to int64 before it is known to fit.
      const auto* p = std::get_if<std::int64_t>(&value);
      const auto* q = std::get_if<double>(&value);
      if (!p && !(q && std::isfinite(*q) && *q == std::floor(*q))) bad_value(owner_, s, given);
      const double d = p ? double(*p) : *q;
      if (d < s.min || d > s.max || (!p && std::fabs(d) >= 9.2e18)) out_of_range(owner_, s, given);
      v = p ? *p : std::int64_t(d);
      break;
    }
    case ParamType::Float: {
      double d;
      if (auto p = std::get_if<double>(&value)) d = *p;
      else if (auto i = std::get_if<std::int64_t>(&value)) d = double(*i);
      else bad_value(owner_, s, given);
      if (!std::isfinite(d)) bad_value(owner_, s, given);  // ranges are finite; inf is never meant
      if (d < s.min || d > s.max) out_of_range(owner_, s, given);
      v = d;
      break;
    }
    case ParamType::Bool:
      if (!std::holds_alternative<bool>(value)) {
        if (auto i = std::get_if<std::int64_t>(&value); i && (*i == 0 || *i == 1)) v = bool(*i);
        else bad_value(owner_, s, given);
      }
      break;
    case ParamType::Enum: {
      auto str = std::get_if<std::string>(&value);
      if (!str) bad_value(owner_, s, given);
      bool ok = false;
      for (const auto& c : s.choices) ok = ok || c == *str;
      if (!ok) out_of_range(owner_, s, given);
      break;
    }
  }
  values_[name] = v;
  given_.insert(name);
}

void ParamSet::set_text(const std::string& name, const std::string& text) {
  const ParamSpec& s = spec(name);
  const std::string given = quoted(text);  // every message repeats what was typed, verbatim
  switch (s.type) {
    case ParamType::Int: {
      errno = 0;
      char* end = nullptr;
      long long i = std::strtoll(text.c_str(), &end, 10);
      if (text.empty() || *end != '\0' || errno == ERANGE) {
        // "5.0" and "1e3" are whole numbers too; "1e20" or twenty digits is out of range.
        char* dend = nullptr;
        double d = std::strtod(text.c_str(), &dend);
        if (text.empty() || *dend != '\0') bad_value(owner_, s, given);
        set_checked(name, d, given);
        return;
      }
      set_checked(name, std::int64_t(i), given);
      return;
    }
    case ParamType::Float: {
      char* end = nullptr;
      double d = std::strtod(text.c_str(), &end);
      if (text.empty() || *end != '\0') bad_value(owner_, s, given);
      set_checked(name, d, given);
      return;
    }
    case ParamType::Bool: {
      std::string t;
      for (char c : text) t += char(std::tolower(static_cast<unsigned char>(c)));
      if (t == "1" || t == "true" || t == "on" || t == "yes") set_checked(name, true, given);
      else if (t == "0" || t == "false" || t == "off" || t == "no") set_checked(name, false, given);
      else bad_value(owner_, s, given);
      return;
    }
    case ParamType::Enum: set_checked(name, text, given); return;
  }
}

namespace {
// A getter of the wrong type is a bug in the filter: a typed Internal error, not std::bad_variant_access.
template <class T>
const T& typed_value(const std::map<std::string, ParamValue>& values, const std::string& owner, const ParamSpec& s,
                     const char* wanted) {
  if (const T* v = std::get_if<T>(&values.at(s.name))) return *v;
  throw Error(Errc::Internal, "parameter '" + s.name + "' of filter '" + owner + "' is " + param_type_name(s.type) +
                                  ", read as " + wanted);
}
}  // namespace

std::int64_t ParamSet::get_int(const std::string& name) const { return typed_value<std::int64_t>(values_, owner_, spec(name), "int"); }
double ParamSet::get_float(const std::string& name) const { return typed_value<double>(values_, owner_, spec(name), "float"); }
bool ParamSet::get_bool(const std::string& name) const { return typed_value<bool>(values_, owner_, spec(name), "bool"); }
const std::string& ParamSet::get_enum(const std::string& name) const { return typed_value<std::string>(values_, owner_, spec(name), "enum"); }

}  // namespace mcr

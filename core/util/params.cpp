#include "util/params.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

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

std::string param_value_text(const ParamValue& v) {
  if (auto i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (auto d = std::get_if<double>(&v)) {
    std::ostringstream os;
    os.precision(9);
    os << *d;
    return os.str();
  }
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

[[noreturn]] void out_of_range(const std::string& owner, const ParamSpec& s, const std::string& value) {
  throw Error(Errc::ParameterOutOfRange,
              "parameter '" + s.name + "' of filter '" + owner + "' must be " + param_range_text(s) + ", got " + value);
}

[[noreturn]] void bad_value(const std::string& owner, const ParamSpec& s, const std::string& text) {
  throw Error(Errc::BadParameterValue, "parameter '" + s.name + "' of filter '" + owner + "' expects " +
                                           param_type_name(s.type) + ", got '" + text + "'");
}

}  // namespace

std::string param_range_text(const ParamSpec& s) {
  switch (s.type) {
    case ParamType::Int: return "[" + std::to_string(std::int64_t(s.min)) + ", " + std::to_string(std::int64_t(s.max)) + "]";
    case ParamType::Float: return "[" + param_value_text(s.min) + ", " + param_value_text(s.max) + "]";
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
  const ParamSpec& s = spec(name);
  const std::string text = param_value_text(value);
  ParamValue v = value;
  switch (s.type) {
    case ParamType::Int: {
      std::int64_t i;
      if (auto p = std::get_if<std::int64_t>(&value)) i = *p;
      else if (auto d = std::get_if<double>(&value); d && std::isfinite(*d) && *d == std::floor(*d) && std::fabs(*d) < 9e15) i = std::int64_t(*d);
      else bad_value(owner_, s, text);
      if (double(i) < s.min || double(i) > s.max) out_of_range(owner_, s, text);
      v = i;
      break;
    }
    case ParamType::Float: {
      double d;
      if (auto p = std::get_if<double>(&value)) d = *p;
      else if (auto i = std::get_if<std::int64_t>(&value)) d = double(*i);
      else bad_value(owner_, s, text);
      if (!std::isfinite(d)) bad_value(owner_, s, text);  // ranges are finite; inf is never meant
      if (d < s.min || d > s.max) out_of_range(owner_, s, text);
      v = d;
      break;
    }
    case ParamType::Bool:
      if (!std::holds_alternative<bool>(value)) {
        if (auto i = std::get_if<std::int64_t>(&value); i && (*i == 0 || *i == 1)) v = bool(*i);
        else bad_value(owner_, s, text);
      }
      break;
    case ParamType::Enum: {
      auto str = std::get_if<std::string>(&value);
      if (!str) bad_value(owner_, s, text);
      bool ok = false;
      for (const auto& c : s.choices) ok = ok || c == *str;
      if (!ok) out_of_range(owner_, s, "'" + *str + "'");
      break;
    }
  }
  values_[name] = v;
  given_.insert(name);
}

void ParamSet::set_text(const std::string& name, const std::string& text) {
  const ParamSpec& s = spec(name);
  switch (s.type) {
    case ParamType::Int: {
      errno = 0;
      char* end = nullptr;
      long long i = std::strtoll(text.c_str(), &end, 10);
      if (text.empty() || *end != '\0' || errno == ERANGE) {
        // Accept "5.0" style integers but nothing fractional.
        char* dend = nullptr;
        double d = std::strtod(text.c_str(), &dend);
        if (text.empty() || *dend != '\0') bad_value(owner_, s, text);
        set(name, d);
        return;
      }
      set(name, std::int64_t(i));
      return;
    }
    case ParamType::Float: {
      char* end = nullptr;
      double d = std::strtod(text.c_str(), &end);
      if (text.empty() || *end != '\0') bad_value(owner_, s, text);
      set(name, d);
      return;
    }
    case ParamType::Bool: {
      std::string t;
      for (char c : text) t += char(std::tolower(static_cast<unsigned char>(c)));
      if (t == "1" || t == "true" || t == "on" || t == "yes") set(name, true);
      else if (t == "0" || t == "false" || t == "off" || t == "no") set(name, false);
      else bad_value(owner_, s, text);
      return;
    }
    case ParamType::Enum: set(name, text); return;
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

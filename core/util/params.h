#pragma once
// One parameter table per filter: name, type, default, range, help. The CLI,
// the OIIO plugin, the Python module and the Blender UI are all generated from it.
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <variant>
#include <vector>

namespace mcr {

enum class ParamType { Int, Float, Bool, Enum };
const char* param_type_name(ParamType t);

using ParamValue = std::variant<std::int64_t, double, bool, std::string>;

struct ParamSpec {
  std::string name;
  ParamType type = ParamType::Float;
  ParamValue default_value;
  double min = 0, max = 0;           // inclusive range for Int and Float
  std::vector<std::string> choices;  // Enum
  std::string help;

  static ParamSpec Int(std::string name, std::int64_t def, std::int64_t lo, std::int64_t hi, std::string help);
  static ParamSpec Float(std::string name, double def, double lo, double hi, std::string help);
  static ParamSpec Bool(std::string name, bool def, std::string help);
  static ParamSpec Enum(std::string name, std::string def, std::vector<std::string> choices, std::string help);
};

using ParamTable = std::vector<ParamSpec>;

// Values of a table, always complete (defaults filled in) and always valid:
// every setter checks name, type and range and throws mcr::Error otherwise.
class ParamSet {
 public:
  ParamSet() = default;
  ParamSet(std::string owner, const ParamTable* table);

  void set(const std::string& name, const ParamValue& value);
  // Parses by the spec's type; an error repeats `text` as given.
  void set_text(const std::string& name, const std::string& text);
  bool has(const std::string& name) const;
  // True when a setter gave this parameter a value (for the unused-setting report).
  bool was_set(const std::string& name) const { return given_.count(name) != 0; }

  std::int64_t get_int(const std::string& name) const;
  double get_float(const std::string& name) const;
  bool get_bool(const std::string& name) const;
  const std::string& get_enum(const std::string& name) const;
  const std::map<std::string, ParamValue>& values() const { return values_; }

 private:
  const ParamSpec& spec(const std::string& name) const;
  // set() with `given`, what the caller gave as messages show it.
  void set_checked(const std::string& name, const ParamValue& value, const std::string& given);
  std::string owner_;
  const ParamTable* table_ = nullptr;
  std::map<std::string, ParamValue> values_;
  std::set<std::string> given_;
};

// Appends "<name> has no effect <why>" to `out` when the setting was given (a default is
// never reported): the unused-setting report of every filter and step.
void report_unused(const ParamSet& params, const std::string& name, const std::string& why,
                   std::vector<std::string>& out);

// The fewest %g digits that read back as v: "0.1", "1e+20", "inf".
std::string number_text(double v);
// v to `digits` significant digits (%g), for figures in notes: "0.81", "18.8", "1.2e-05".
std::string rounded_text(double v, int digits);
std::string param_value_text(const ParamValue& v);  // "5", "0.25", "true", "gaussian"
// "[0, 64]" for numbers (">= 0 (no upper bound)" when a bound is infinite or the type's
// end), "one of: a, b" for enums, "" for bools.
std::string param_range_text(const ParamSpec& s);

}  // namespace mcr

// ParamSet: parsing, types, ranges and unknown names, with their error codes and messages.
#include "util/params.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "expect_error.h"
#include "util/error.h"

namespace mcr {
namespace {

using testutil::contains;
using testutil::expect_error;

const ParamTable& table() {
  static const ParamTable t = {
      ParamSpec::Int("radius", 2, 0, 64, "window half width"),
      ParamSpec::Float("sigma", 0.5, 0.01, 10.0, "spatial sigma"),
      ParamSpec::Bool("albedo", true, "use albedo"),
      ParamSpec::Enum("kernel", "gauss", {"gauss", "box", "tent"}, "kernel shape"),
  };
  return t;
}

ParamSet params() { return ParamSet("testfilter", &table()); }

TEST(ParamsTest, DefaultsAreFilledIn) {
  const ParamSet p = params();
  EXPECT_EQ(p.get_int("radius"), 2);
  EXPECT_DOUBLE_EQ(p.get_float("sigma"), 0.5);
  EXPECT_TRUE(p.get_bool("albedo"));
  EXPECT_EQ(p.get_enum("kernel"), "gauss");
  EXPECT_EQ(p.values().size(), 4u);
  EXPECT_TRUE(p.has("radius"));
  EXPECT_FALSE(p.has("nosuch"));
}

TEST(ParamsTest, SetTextParsesEachType) {
  ParamSet p = params();
  p.set_text("radius", "7");
  p.set_text("sigma", "2.25");
  p.set_text("albedo", "off");
  p.set_text("kernel", "tent");
  EXPECT_EQ(p.get_int("radius"), 7);
  EXPECT_DOUBLE_EQ(p.get_float("sigma"), 2.25);
  EXPECT_FALSE(p.get_bool("albedo"));
  EXPECT_EQ(p.get_enum("kernel"), "tent");
  p.set_text("radius", "5.0");  // an integral float is an int
  EXPECT_EQ(p.get_int("radius"), 5);
  p.set_text("sigma", "3");  // an int is a float
  EXPECT_DOUBLE_EQ(p.get_float("sigma"), 3.0);
  for (const char* t : {"1", "true", "TRUE", "on", "yes"}) {
    p.set_text("albedo", t);
    EXPECT_TRUE(p.get_bool("albedo")) << t;
  }
  for (const char* t : {"0", "false", "Off", "no"}) {
    p.set_text("albedo", t);
    EXPECT_FALSE(p.get_bool("albedo")) << t;
  }
}

TEST(ParamsTest, RangeEndsAreInclusive) {
  ParamSet p = params();
  p.set_text("radius", "0");
  EXPECT_EQ(p.get_int("radius"), 0);
  p.set_text("radius", "64");
  EXPECT_EQ(p.get_int("radius"), 64);
  p.set_text("sigma", "0.01");
  p.set_text("sigma", "10");
  EXPECT_DOUBLE_EQ(p.get_float("sigma"), 10.0);
}

TEST(ParamsTest, UnknownNameNamesParameterFilterAndKnownNames) {
  ParamSet p = params();
  std::string msg = expect_error(Errc::UnknownParameter, [&] { p.set_text("nosuch", "1"); });
  EXPECT_TRUE(contains(msg, "'nosuch'")) << msg;
  EXPECT_TRUE(contains(msg, "'testfilter'")) << msg;
  EXPECT_TRUE(contains(msg, "radius")) << msg;
  msg = expect_error(Errc::UnknownParameter, [&] { p.set("Radius", std::int64_t(1)); });  // names are exact
  EXPECT_TRUE(contains(msg, "'Radius'")) << msg;
  expect_error(Errc::UnknownParameter, [&] { p.get_int("nosuch"); });
  expect_error(Errc::UnknownParameter, [&] { p.get_float(""); });
}

TEST(ParamsTest, FilterWithoutParametersSaysSo) {
  static const ParamTable empty;
  ParamSet p("plain", &empty);
  const std::string msg = expect_error(Errc::UnknownParameter, [&] { p.set_text("radius", "1"); });
  EXPECT_TRUE(contains(msg, "'plain'")) << msg;
  EXPECT_TRUE(contains(msg, "takes none")) << msg;
}

TEST(ParamsTest, OutOfRangeNamesParameterFilterRangeAndValue) {
  ParamSet p = params();
  std::string msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("radius", "-1"); });
  EXPECT_TRUE(contains(msg, "'radius'")) << msg;
  EXPECT_TRUE(contains(msg, "'testfilter'")) << msg;
  EXPECT_TRUE(contains(msg, "[0, 64]")) << msg;
  EXPECT_TRUE(contains(msg, "-1")) << msg;
  msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("radius", "1000"); });
  EXPECT_TRUE(contains(msg, "1000")) << msg;
  expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("radius", "65"); });
  msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("sigma", "0.001"); });
  EXPECT_TRUE(contains(msg, "'sigma'")) << msg;
  expect_error(Errc::ParameterOutOfRange, [&] { p.set("sigma", 10.5); });
  expect_error(Errc::ParameterOutOfRange, [&] { p.set("radius", std::int64_t(-5)); });
  msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("kernel", "median"); });
  EXPECT_TRUE(contains(msg, "'kernel'")) << msg;
  EXPECT_TRUE(contains(msg, "median")) << msg;
  EXPECT_TRUE(contains(msg, "gauss, box, tent")) << msg;
}

TEST(ParamsTest, BadValuesNameParameterTypeAndText) {
  ParamSet p = params();
  std::string msg = expect_error(Errc::BadParameterValue, [&] { p.set_text("radius", "abc"); });
  EXPECT_TRUE(contains(msg, "'radius'")) << msg;
  EXPECT_TRUE(contains(msg, "'testfilter'")) << msg;
  EXPECT_TRUE(contains(msg, "int")) << msg;
  EXPECT_TRUE(contains(msg, "'abc'")) << msg;
  for (const char* t : {"", "2.5", "3x", "nan", "inf", "1e400", "--2"})
    expect_error(Errc::BadParameterValue, [&] { p.set_text("radius", t); });
  for (const char* t : {"", "abc", "nan", "inf", "-inf", "1e999", "0.5.5"})
    expect_error(Errc::BadParameterValue, [&] { p.set_text("sigma", t); });
  msg = expect_error(Errc::BadParameterValue, [&] { p.set_text("albedo", "maybe"); });
  EXPECT_TRUE(contains(msg, "'albedo'")) << msg;
  EXPECT_TRUE(contains(msg, "bool")) << msg;
  expect_error(Errc::BadParameterValue, [&] { p.set_text("albedo", "2"); });
}

// Issue 13: the message repeats what the user typed, verbatim, never a reformatted double.
TEST(ParamsTest, MessagesRepeatTheTypedText) {
  ParamSet p = params();
  for (const char* t : {"1e20", "100000000000000000000", "1E20", "65.0", "-0.5e1"}) {
    const std::string msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("radius", t); });
    EXPECT_TRUE(contains(msg, "'" + std::string(t) + "'")) << msg;
    EXPECT_TRUE(contains(msg, "[0, 64]")) << msg;
    EXPECT_FALSE(contains(msg, "e+20")) << msg;
  }
  for (const char* t : {"1e999", "-1e999", "2.50", "0x"}) {
    const std::string msg = expect_error(Errc::BadParameterValue, [&] { p.set_text("radius", t); });
    EXPECT_TRUE(contains(msg, "'" + std::string(t) + "'")) << msg;
    EXPECT_TRUE(contains(msg, "[0, 64]")) << msg;  // the valid range, also for a type error
  }
  for (const char* t : {"1e999", "1.0e+400", "NaN"}) {
    const std::string msg = expect_error(Errc::BadParameterValue, [&] { p.set_text("sigma", t); });
    EXPECT_TRUE(contains(msg, "'" + std::string(t) + "'")) << msg;
    EXPECT_FALSE(contains(msg, "'inf'")) << msg;
  }
  std::string msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("sigma", "0.0010"); });
  EXPECT_TRUE(contains(msg, "'0.0010'")) << msg;
  EXPECT_TRUE(contains(msg, "[0.01, 10]")) << msg;
  msg = expect_error(Errc::BadParameterValue, [&] { p.set_text("albedo", "Maybe"); });
  EXPECT_TRUE(contains(msg, "'Maybe'")) << msg;
  EXPECT_TRUE(contains(msg, "true")) << msg;  // the accepted spellings
  // A typed value (Python, an OIIO float attribute) has no text: printed readably, unquoted.
  msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set("radius", 1e20); });
  EXPECT_TRUE(contains(msg, "got 1e+20")) << msg;
  msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set("sigma", 0.1 + 10.0); });
  EXPECT_TRUE(contains(msg, "got 10.1")) << msg;  // the shortest text that reads back, not 10.0999999
  msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set("radius", std::int64_t(-3)); });
  EXPECT_TRUE(contains(msg, "got -3")) << msg;
}

// Ranges print readably: shortest digits, and an infinite or type-end bound as "no bound"
// instead of 300 digits of DBL_MAX.
TEST(ParamsTest, RangesPrintReadably) {
  const double inf = std::numeric_limits<double>::infinity(), big = std::numeric_limits<double>::max();
  const auto i64max = std::numeric_limits<std::int64_t>::max();
  static const ParamTable t = {
      ParamSpec::Float("clamp", 0.0, 0.0, 1e30, ""),
      ParamSpec::Float("gain", 1.0, 0.0, big, ""),
      ParamSpec::Float("offset", 0.0, -inf, 5.0, ""),
      ParamSpec::Float("any", 0.0, -big, inf, ""),
      ParamSpec::Int("count", 1, 1, i64max, ""),
      ParamSpec::Float("tenth", 0.5, 0.1, 0.3, ""),
  };
  EXPECT_EQ(param_range_text(t[0]), "[0, 1e+30]");
  EXPECT_EQ(param_range_text(t[1]), ">= 0 (no upper bound)");
  EXPECT_EQ(param_range_text(t[2]), "<= 5 (no lower bound)");
  EXPECT_EQ(param_range_text(t[3]), "any number");
  EXPECT_EQ(param_range_text(t[4]), ">= 1 (no upper bound)");
  EXPECT_EQ(param_range_text(t[5]), "[0.1, 0.3]");
  ParamSet p("ranges", &t);
  std::string msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("gain", "-1"); });
  EXPECT_TRUE(contains(msg, "must be >= 0 (no upper bound), got '-1'")) << msg;
  msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("count", "0"); });
  EXPECT_TRUE(contains(msg, ">= 1 (no upper bound)")) << msg;
  p.set_text("count", "9223372036854775807");
  EXPECT_EQ(p.get_int("count"), i64max);
  msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("count", "1e19"); });
  EXPECT_TRUE(contains(msg, "'1e19'")) << msg;
  msg = expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("clamp", "2e30"); });
  EXPECT_TRUE(contains(msg, "must be in [0, 1e+30], got '2e30'")) << msg;
  EXPECT_LT(msg.size(), 120u) << msg;
  for (const std::string& m : {msg, param_range_text(t[1])}) EXPECT_EQ(m.find("1797"), std::string::npos) << m;
}

TEST(ParamsTest, TypedSetChecksTheType) {
  ParamSet p = params();
  expect_error(Errc::BadParameterValue, [&] { p.set("radius", std::string("3")); });
  expect_error(Errc::BadParameterValue, [&] { p.set("radius", 2.5); });
  expect_error(Errc::BadParameterValue, [&] { p.set("radius", true); });
  expect_error(Errc::BadParameterValue, [&] { p.set("sigma", std::string("1")); });
  expect_error(Errc::BadParameterValue, [&] { p.set("sigma", std::numeric_limits<double>::quiet_NaN()); });
  expect_error(Errc::BadParameterValue, [&] { p.set("albedo", std::int64_t(2)); });
  expect_error(Errc::BadParameterValue, [&] { p.set("albedo", 1.0); });
  expect_error(Errc::BadParameterValue, [&] { p.set("kernel", std::int64_t(1)); });
  // Conversions that lose nothing are accepted.
  p.set("radius", 4.0);
  EXPECT_EQ(p.get_int("radius"), 4);
  p.set("sigma", std::int64_t(2));
  EXPECT_DOUBLE_EQ(p.get_float("sigma"), 2.0);
  p.set("albedo", std::int64_t(0));
  EXPECT_FALSE(p.get_bool("albedo"));
}

TEST(ParamsTest, FailedSetKeepsThePreviousValue) {
  ParamSet p = params();
  p.set_text("radius", "9");
  expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("radius", "100"); });
  expect_error(Errc::BadParameterValue, [&] { p.set_text("radius", "x"); });
  EXPECT_EQ(p.get_int("radius"), 9);
  expect_error(Errc::ParameterOutOfRange, [&] { p.set_text("kernel", "nope"); });
  EXPECT_EQ(p.get_enum("kernel"), "gauss");
}

TEST(ParamsTest, GetterOfTheWrongTypeIsATypedError) {
  const ParamSet p = params();
  const std::string msg = expect_error(Errc::Internal, [&] { p.get_float("radius"); });
  EXPECT_TRUE(contains(msg, "'radius'")) << msg;
  expect_error(Errc::Internal, [&] { p.get_int("sigma"); });
  expect_error(Errc::Internal, [&] { p.get_enum("albedo"); });
  expect_error(Errc::Internal, [&] { p.get_bool("kernel"); });
}

TEST(ParamsTest, TextForms) {
  EXPECT_EQ(param_value_text(ParamValue(std::int64_t(5))), "5");
  EXPECT_EQ(param_value_text(ParamValue(0.25)), "0.25");
  EXPECT_EQ(param_value_text(ParamValue(0.1)), "0.1");
  EXPECT_EQ(param_value_text(ParamValue(1.0 / 3.0)), "0.3333333333333333");  // reads back exactly
  EXPECT_EQ(param_value_text(ParamValue(1e20)), "1e+20");
  EXPECT_EQ(number_text(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(param_value_text(ParamValue(true)), "true");
  EXPECT_EQ(param_value_text(ParamValue(std::string("gauss"))), "gauss");
  EXPECT_EQ(param_range_text(table()[0]), "[0, 64]");
  EXPECT_EQ(param_range_text(table()[1]), "[0.01, 10]");
  EXPECT_EQ(param_range_text(table()[2]), "");
  EXPECT_EQ(param_range_text(table()[3]), "one of: gauss, box, tent");
  EXPECT_STREQ(param_type_name(ParamType::Int), "int");
  EXPECT_STREQ(param_type_name(ParamType::Enum), "enum");
}

}  // namespace
}  // namespace mcr

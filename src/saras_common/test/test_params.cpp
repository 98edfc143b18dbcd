// Params: typed reading and validation of start-up parameters, without a ROS master (a map stands in
// for the parameter server).
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "saras_common/params.h"

using saras_common::ParamError;
using saras_common::Params;

namespace
{
class ParamsTest : public ::testing::Test
{
protected:
  std::map<std::string, XmlRpc::XmlRpcValue> server;
  Params params{ [this](const std::string& n, XmlRpc::XmlRpcValue& v) {
                  auto it = server.find(n);
                  if (it == server.end())
                    return false;
                  v = it->second;
                  return true;
                },
                 [](const std::string& n) { return "/ns/node/" + n; } };

  /// The message of the ParamError that @p f throws ("" if none).
  template <class F>
  std::string errorOf(F f)
  {
    try
    {
      f();
    }
    catch (const ParamError& e)
    {
      return e.what();
    }
    return "";
  }
};

XmlRpc::XmlRpcValue list(std::initializer_list<XmlRpc::XmlRpcValue> items)
{
  XmlRpc::XmlRpcValue x;
  x.setSize(static_cast<int>(items.size()));
  int i = 0;
  for (const auto& it : items)
    x[i++] = it;
  return x;
}
}  // namespace

TEST_F(ParamsTest, AbsentParametersTakeTheirDefaults)
{
  EXPECT_EQ(params.number("timeout", 0.03, "s", { saras_common::positive() }), 0.03);
  EXPECT_EQ(params.integer("port", 5005, "", { saras_common::inRange(0, 65535) }), 5005);
  EXPECT_TRUE(params.flag("publish_tf", true));
  EXPECT_EQ(params.text("mode", "shared"), "shared");
  EXPECT_EQ(params.numbers("gains", { 1, 2, 3 }, "N/m", {}, 3), (std::vector<double>{ 1, 2, 3 }));
  EXPECT_EQ(params.texts("channels", { "left", "right" }), (std::vector<std::string>{ "left", "right" }));
  EXPECT_FALSE(params.has("timeout"));
}

TEST_F(ParamsTest, PresentParametersAreRead)
{
  server["timeout"] = 0.5;
  server["rate"] = 250;  // an integer where a number is expected
  server["port"] = 6000;
  server["publish_tf"] = false;
  server["mode"] = std::string("manager");
  server["gains"] = list({ 4.0, 5, 6.5 });
  server["damping"] = 2.0;  // one number for every entry
  server["channels"] = list({ std::string("left") });
  EXPECT_EQ(params.number("timeout", 0.03, "s", { saras_common::positive() }), 0.5);
  EXPECT_EQ(params.number("rate", 1000.0, "Hz"), 250.0);
  EXPECT_EQ(params.integer("port", 5005, ""), 6000);
  EXPECT_FALSE(params.flag("publish_tf", true));
  EXPECT_EQ(params.text("mode", "shared", { saras_common::oneOf({ "manager", "shared" }) }), "manager");
  EXPECT_EQ(params.numbers("gains", { 1, 2, 3 }, "N/m", {}, 3), (std::vector<double>{ 4, 5, 6.5 }));
  EXPECT_EQ(params.numbers("damping", { 1, 2, 3 }, "N s/m", {}, 3), (std::vector<double>{ 2, 2, 2 }));
  EXPECT_EQ(params.texts("channels", { "left", "right" }), (std::vector<std::string>{ "left" }));
  EXPECT_TRUE(params.has("timeout"));
}

TEST_F(ParamsTest, ErrorNamesParameterValueUnitAndRule)
{
  server["timeout"] = -1.0;
  EXPECT_EQ(errorOf([&] { params.number("timeout", 0.03, "s", { saras_common::positive() }); }),
            "parameter /ns/node/timeout = -1 [s] is invalid: must be > 0");
  server["port"] = 70000;
  EXPECT_EQ(errorOf([&] { params.integer("port", 5005, "", { saras_common::inRange(0, 65535) }); }),
            "parameter /ns/node/port = 70000 is invalid: must be in [0, 65535]");
  try
  {
    params.number("timeout", 0.03, "s", { saras_common::positive() });
    FAIL() << "no exception";
  }
  catch (const ParamError& e)
  {
    EXPECT_EQ(e.name(), "/ns/node/timeout");
    EXPECT_EQ(e.rule(), "> 0");
  }
}

TEST_F(ParamsTest, WrongTypesAreRejectedNotConverted)
{
  server["timeout"] = std::string("fast");
  EXPECT_EQ(errorOf([&] { params.number("timeout", 0.03, "s"); }),
            "parameter /ns/node/timeout = 'fast' [s] is invalid: must be a number");
  server["port"] = 5005.0;
  EXPECT_EQ(errorOf([&] { params.integer("port", 1, ""); }),
            "parameter /ns/node/port = 5005 is invalid: must be an integer");
  server["publish_tf"] = 1;
  EXPECT_EQ(errorOf([&] { params.flag("publish_tf", true); }),
            "parameter /ns/node/publish_tf = 1 is invalid: must be true or false");
  server["mode"] = true;
  EXPECT_EQ(errorOf([&] { params.text("mode", "shared"); }),
            "parameter /ns/node/mode = true is invalid: must be a string");
  server["gains"] = list({ 1.0, 2.0 });
  EXPECT_EQ(errorOf([&] { params.numbers("gains", { 1, 2, 3 }, "N/m", {}, 3); }),
            "parameter /ns/node/gains = a list of 2 [N/m] is invalid: must be a list of 3 numbers or one number");
  server["gains"] = list({ 1.0, std::string("x"), 3.0 });
  EXPECT_NE(errorOf([&] { params.numbers("gains", { 1, 2, 3 }, "N/m"); }), "");
  server["channels"] = list({ std::string("left"), 3 });
  EXPECT_EQ(errorOf([&] { params.texts("channels", {}); }),
            "parameter /ns/node/channels = a list of 2 is invalid: must be a list of strings");
}

TEST_F(ParamsTest, RulesAreChecked)
{
  using namespace saras_common;
  server["x"] = 0.0;
  EXPECT_NE(errorOf([&] { params.number("x", 1, "m", { positive() }); }), "");
  EXPECT_EQ(params.number("x", 1, "m", { nonNegative() }), 0.0);
  EXPECT_EQ(errorOf([&] { params.number("x", 1, "m", { atLeast(0.5) }); }),
            "parameter /ns/node/x = 0 [m] is invalid: must be >= 0.5");
  server["x"] = 2.5;
  EXPECT_EQ(errorOf([&] { params.number("x", 1, "m", { nonNegative(), atMost(2) }); }),
            "parameter /ns/node/x = 2.5 [m] is invalid: must be >= 0 and <= 2");
  EXPECT_EQ(params.number("x", 1, "m", { inRange(2.5, 2.5) }), 2.5);  // bounds are inclusive
  server["mode"] = std::string("own");
  EXPECT_EQ(errorOf([&] { params.text("mode", "shared", { oneOf({ "manager", "shared" }) }); }),
            "parameter /ns/node/mode = 'own' is invalid: must be one of manager, shared");
  server["frame"] = std::string("");
  EXPECT_EQ(errorOf([&] { params.text("frame", "world", { nonEmpty() }); }),
            "parameter /ns/node/frame = '' is invalid: must be non-empty");
  server["gains"] = list({ 1.0, -2.0, 3.0 });
  EXPECT_EQ(errorOf([&] { params.numbers("gains", {}, "N/m", { nonNegative() }); }),
            "parameter /ns/node/gains[1] = -2 [N/m] is invalid: must be >= 0");
}

TEST_F(ParamsTest, NonFiniteNumbersAreRejected)
{
  server["x"] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(errorOf([&] { params.number("x", 1, "s"); }), "parameter /ns/node/x = nan [s] is invalid: must be finite");
  server["x"] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(errorOf([&] { params.number("x", 1, "s", { saras_common::positive() }); }),
            "parameter /ns/node/x = inf [s] is invalid: must be finite and > 0");
  // a bad default is reported too (a programming error, caught at start-up)
  EXPECT_NE(errorOf([&] { params.number("absent", -1, "s", { saras_common::positive() }); }), "");
}

TEST_F(ParamsTest, FailReportsRulesAcrossParameters)
{
  EXPECT_EQ(errorOf([&] { params.fail("resync_after", 0.01, "s", ">= timeout (0.03 s)"); }),
            "parameter /ns/node/resync_after = 0.01 [s] is invalid: must be >= timeout (0.03 s)");
  EXPECT_EQ(params.resolve("a/b"), "/ns/node/a/b");
}

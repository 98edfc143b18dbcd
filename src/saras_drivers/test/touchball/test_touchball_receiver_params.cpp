/**
 * @file test_touchball_receiver_params.cpp
 * @brief readReceiverConfig through saras_common::Params over a map (no roscore): defaults, derived
 *        source filter, and a message naming parameter, value, unit and rule for bad values.
 */
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "saras_drivers/touchball_receiver_params.h"

using namespace saras_drivers::touchball;

namespace
{
using Values = std::map<std::string, XmlRpc::XmlRpcValue>;

/// Parameters @p given, plus a key_file unless given (or @p with_key is false).
saras_common::Params paramsOf(const Values& given, bool with_key = true)
{
  Values values = given;
  if (with_key)
    values.emplace("key_file", XmlRpc::XmlRpcValue("/etc/saras/console.key"));
  return saras_common::Params(
      [values](const std::string& n, XmlRpc::XmlRpcValue& v) {
        const auto it = values.find(n);
        if (it == values.end())
          return false;
        v = it->second;
        return true;
      },
      [](const std::string& n) { return "/touchball_receiver/" + n; });
}

/// The error message for @p values, or "accepted".
std::string error(const Values& values, bool with_key = true)
{
  try
  {
    readReceiverConfig(paramsOf(values, with_key));
  }
  catch (const saras_common::ParamError& e)
  {
    return e.what();
  }
  return "accepted";
}
}  // namespace

TEST(ReceiverParams, DefaultsAndDerivedSourceFilter)
{
  const ReceiverConfig c = readReceiverConfig(paramsOf({}));
  EXPECT_EQ(c.port, 5005);
  EXPECT_DOUBLE_EQ(c.link.timeout, 0.03);
  EXPECT_FALSE(c.link.any_source);
  EXPECT_EQ(c.link.source_ip, 0x7f000001u);
  const ReceiverConfig any = readReceiverConfig(paramsOf({ { "allowed_source", XmlRpc::XmlRpcValue("*") },
                                                          { "timeout", XmlRpc::XmlRpcValue(1) },
                                                          { "resync_after", XmlRpc::XmlRpcValue(2.5) } }));
  EXPECT_TRUE(any.link.any_source);
  EXPECT_DOUBLE_EQ(any.link.timeout, 1.0);  // an integer is a number
  EXPECT_DOUBLE_EQ(any.link.resync_after, 2.5);
}

TEST(ReceiverParams, BadValuesNameParameterValueUnitAndRule)
{
  EXPECT_EQ(error({ { "timeout", XmlRpc::XmlRpcValue(-0.01) } }),
            "parameter /touchball_receiver/timeout = -0.01 [s] is invalid: must be > 0");
  EXPECT_EQ(error({ { "resync_after", XmlRpc::XmlRpcValue(0.01) } }),
            "parameter /touchball_receiver/resync_after = 0.01 [s] is invalid: must be >= ~timeout");
  EXPECT_EQ(error({ { "port", XmlRpc::XmlRpcValue(70000) } }),
            "parameter /touchball_receiver/port = 70000 is invalid: must be in [0, 65535]");
  EXPECT_EQ(error({ { "bind_address", XmlRpc::XmlRpcValue("host") } }),
            "parameter /touchball_receiver/bind_address = 'host' is invalid: must be an IPv4 address");
  EXPECT_NE(error({ { "allowed_source", XmlRpc::XmlRpcValue("1.2.3") } }).find("allowed_source = '1.2.3'"),
            std::string::npos);
  EXPECT_NE(error({ { "max_force", XmlRpc::XmlRpcValue(-1.0) } }).find("[N] is invalid"), std::string::npos);
  EXPECT_NE(error({ { "publish_tf", XmlRpc::XmlRpcValue(1) } }).find("true or false"), std::string::npos);
  EXPECT_NE(error({ { "realtime_priority", XmlRpc::XmlRpcValue(100) } }).find("realtime_priority"), std::string::npos);
  EXPECT_NE(error({ { "status_rate", XmlRpc::XmlRpcValue(0.0) } }).find("status_rate"), std::string::npos);
  EXPECT_EQ(error({ { "joint_states_rate", XmlRpc::XmlRpcValue(0.0) } }), "accepted");  // 0 = off
  EXPECT_NE(error({ { "tf_rate", XmlRpc::XmlRpcValue(-1.0) } }).find("tf_rate = -1 [Hz] is invalid"), std::string::npos);
  EXPECT_EQ(error({ { "tf_rate", XmlRpc::XmlRpcValue(0.0) } }), "accepted");  // 0 = every packet
  EXPECT_NE(error({}, false).find("/touchball_receiver/key_file"), std::string::npos);  // no key: no start
}

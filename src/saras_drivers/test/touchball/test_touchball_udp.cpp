/**
 * @file test_touchball_udp.cpp
 * @brief UdpSocket on the loopback interface (no roscore): bind, wait with a deadline, receive with
 *        the source, send, truncation of oversized datagrams, errors; address helpers.
 */
#include <gtest/gtest.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "saras_drivers/touchball_udp.h"

using namespace saras_drivers::touchball;

namespace
{
constexpr std::uint32_t kLoopback = 0x7f000001;

double seconds()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

TEST(TouchballUdp, ParsesAndFormatsAddresses)
{
  std::uint32_t ip = 0;
  EXPECT_TRUE(parseIpv4("127.0.0.1", ip));
  EXPECT_EQ(ip, kLoopback);
  EXPECT_TRUE(parseIpv4("10.1.2.3", ip));
  EXPECT_EQ(ip, 0x0a010203u);
  EXPECT_FALSE(parseIpv4("localhost", ip));
  EXPECT_FALSE(parseIpv4("", ip));
  EXPECT_FALSE(parseIpv4("1.2.3.256", ip));
  char b[32];
  EXPECT_STREQ(formatEndpoint(Endpoint{ 0x0a010203u, 5005 }, b, sizeof b), "10.1.2.3:5005");
  const Endpoint d = commandDestination(Endpoint{ kLoopback, 40000 }, 5006);
  EXPECT_EQ(d.ip, kLoopback);
  EXPECT_EQ(d.port, 5006);
  EXPECT_EQ(commandDestination(Endpoint{ kLoopback, 40000 }, 0).port, 40000);
}

TEST(TouchballUdp, ExchangesDatagramsWithTheirSource)
{
  UdpSocket rx("127.0.0.1", 0), tx("127.0.0.1", 0);
  ASSERT_NE(rx.localPort(), 0);
  std::vector<std::uint8_t> buf(64);
  Endpoint src;
  EXPECT_EQ(rx.receive(buf.data(), buf.size(), src), -EAGAIN);  // nothing queued: never blocks
  const std::uint8_t msg[5] = { 1, 2, 3, 4, 5 };
  ASSERT_EQ(tx.sendTo(msg, sizeof msg, Endpoint{ kLoopback, rx.localPort() }), 0);
  EXPECT_EQ(rx.wait(5.0), 1);
  ASSERT_EQ(rx.receive(buf.data(), buf.size(), src), 5);
  EXPECT_EQ(std::memcmp(buf.data(), msg, 5), 0);
  EXPECT_EQ(src.ip, kLoopback);
  EXPECT_EQ(src.port, tx.localPort());
  // answer to the source
  ASSERT_EQ(rx.sendTo(msg, 3, src), 0);
  EXPECT_EQ(tx.wait(5.0), 1);
  EXPECT_EQ(tx.receive(buf.data(), buf.size(), src), 3);
  EXPECT_EQ(src.port, rx.localPort());
}

TEST(TouchballUdp, OversizedDatagramIsTruncatedToTheBuffer)
{
  UdpSocket rx("127.0.0.1", 0), tx("127.0.0.1", 0);
  const std::vector<std::uint8_t> big(300, 7);
  ASSERT_EQ(tx.sendTo(big.data(), big.size(), Endpoint{ kLoopback, rx.localPort() }), 0);
  ASSERT_EQ(rx.wait(5.0), 1);
  std::vector<std::uint8_t> buf(200);
  Endpoint src;
  EXPECT_EQ(rx.receive(buf.data(), buf.size(), src), 200);
}

TEST(TouchballUdp, WaitTimesOutWithoutData)
{
  UdpSocket rx("127.0.0.1", 0);
  EXPECT_EQ(rx.wait(0.0), 0);
  const double t0 = seconds();
  EXPECT_EQ(rx.wait(0.02), 0);
  EXPECT_GE(seconds() - t0, 0.019);  // waited for the deadline (no upper bound: the host may be loaded)
}

TEST(TouchballUdp, BindErrorsNameTheAddress)
{
  UdpSocket taken("127.0.0.1", 0);
  try
  {
    UdpSocket second("127.0.0.1", taken.localPort());
    FAIL() << "bound a port in use";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("127.0.0.1:" + std::to_string(taken.localPort())), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(UdpSocket("not-an-address", 0), std::invalid_argument);
}

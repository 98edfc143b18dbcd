/**
 * @file test_touchball_receiver_core.cpp
 * @brief ReceiverCore (receive-thread / callback-queue hand-off), RateMeter, the status text and
 *        the /diagnostics key/values (no roscore).
 */
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <thread>

#include "packet_builder.h"
#include "saras_drivers/touchball_receiver_core.h"

using namespace saras_drivers::touchball;
using touchball_test::Builder;

namespace
{
constexpr std::uint32_t kLocal = 0x7f000001;

LinkParams linkParams()
{
  LinkParams p;
  p.source_ip = kLocal;
  p.timeout = 0.03;
  return p;
}

std::uint64_t testNonce()
{
  return touchball_test::kSession;
}

/// Answer the test console's hello: the session kSession is open.
void openSession(ReceiverCore& core)
{
  AcceptedPacket out;
  bool resumed = false;
  const auto h = touchball_test::hello();
  ASSERT_EQ(core.accept(h.data(), h.size(), kLocal, 0.0, 0, out, resumed), Reject::NONE);
  ASSERT_EQ(out.kind, Accepted::HELLO);
  ASSERT_EQ(out.session, touchball_test::kSession);
  ASSERT_EQ(out.console_nonce, touchball_test::kConsoleNonce);
  ASSERT_FALSE(resumed);
}

std::map<std::string, std::string> asMap(const HealthReport& r)
{
  return std::map<std::string, std::string>(r.values.begin(), r.values.end());
}
}  // namespace

TEST(ReceiverCore, AcceptHandsOutPacketTwistAndCommands)
{
  ReceiverCore core(linkParams(), WrenchLimits{ 2.0, 0.0, 0.1 }, touchball_test::testKey(), 3.0, testNonce);
  openSession(core);
  const double force[3] = { 3.0, 0.0, 4.0 }, torque[3] = { 1.0, 0.0, 0.0 };
  EXPECT_TRUE(core.setWrench(kLeft, force, torque, 0.0));
  AcceptedPacket out;
  bool resumed = false;
  const auto d = Builder(7, 1.0).f64(28, -0.11).done();
  ASSERT_EQ(core.accept(d.data(), d.size(), kLocal, 0.05, 123456789, out, resumed), Reject::NONE);
  EXPECT_TRUE(resumed);  // the link starts STALE
  EXPECT_EQ(out.packet.seq, 7u);
  EXPECT_DOUBLE_EQ(out.packet.devices[kLeft].position[0], -0.11);
  EXPECT_TRUE(out.commands[kLeft].enabled);
  EXPECT_NEAR(std::hypot(out.commands[kLeft].force[0], out.commands[kLeft].force[2]), 2.0, 1e-12);  // clamped
  EXPECT_DOUBLE_EQ(out.commands[kLeft].torque[0], 0.0);
  EXPECT_FALSE(out.commands[kRight].enabled);
  // the next packet 10 ms later (sender time): twist from the position step, link already OK
  const auto e = Builder(8, 1.01).f64(28, -0.10).done();
  ASSERT_EQ(core.accept(e.data(), e.size(), kLocal, 0.06, 0, out, resumed), Reject::NONE);
  EXPECT_FALSE(resumed);
  EXPECT_GT(out.linear[kLeft][0], 0.0);
  // the command aged out (> wrench_timeout since it was set)
  const auto f = Builder(9, 1.02).done();
  ASSERT_EQ(core.accept(f.data(), f.size(), kLocal, 0.2, 0, out, resumed), Reject::NONE);
  EXPECT_FALSE(out.commands[kLeft].enabled);
  // a rejected datagram leaves the handed-out packet alone
  out.packet.seq = 99;
  EXPECT_EQ(core.accept(f.data(), f.size(), kLocal, 0.21, 0, out, resumed), Reject::DUPLICATE);
  EXPECT_EQ(out.packet.seq, 99u);
}

TEST(ReceiverCore, WatchdogDeclaresStaleOnceAndResumes)
{
  ReceiverCore core(linkParams(), WrenchLimits(), touchball_test::testKey(), 3.0, testNonce);
  openSession(core);
  EXPECT_TRUE(core.stale());
  EXPECT_FALSE(core.watchdog(100.0));  // never streamed: already STALE, nothing to declare
  AcceptedPacket out;
  bool resumed = false;
  const auto d = Builder(1, 1.0).done();
  ASSERT_EQ(core.accept(d.data(), d.size(), kLocal, 10.0, 0, out, resumed), Reject::NONE);
  EXPECT_FALSE(core.stale());
  EXPECT_NEAR(core.waitTime(10.01, 0.1), 0.02, 1e-12);  // until the deadline
  EXPECT_FALSE(core.watchdog(10.029));
  EXPECT_TRUE(core.watchdog(10.031));  // deadline passed: STALE, exactly once
  EXPECT_FALSE(core.watchdog(10.04));
  EXPECT_TRUE(core.stale());
  EXPECT_DOUBLE_EQ(core.waitTime(10.04, 0.1), 0.1);  // idle wake while STALE
  const auto e = Builder(2, 1.001).done();
  ASSERT_EQ(core.accept(e.data(), e.size(), kLocal, 10.05, 0, out, resumed), Reject::NONE);
  EXPECT_TRUE(resumed);
  EXPECT_FALSE(core.stale());
}

TEST(ReceiverCore, HealthCountsEveryRejectionByReason)
{
  ReceiverCore core(linkParams(), WrenchLimits(), touchball_test::testKey(), 3.0, testNonce);
  openSession(core);
  AcceptedPacket out;
  bool resumed;
  const auto good = Builder(1, 1.0).done();
  auto bad_mac = good;
  bad_mac[30] ^= 1;
  core.accept(good.data(), good.size(), kLocal, 1.0, 0, out, resumed);
  core.accept(good.data(), good.size(), kLocal, 1.001, 0, out, resumed);            // duplicate
  core.accept(bad_mac.data(), bad_mac.size(), kLocal, 1.002, 0, out, resumed);      // mac
  core.accept(good.data(), 20, kLocal, 1.003, 0, out, resumed);                     // size
  core.accept(good.data(), good.size(), 0x0a000001, 1.004, 0, out, resumed);       // foreign source
  const double nan3[3] = { std::nan(""), 0.0, 0.0 }, zero[3] = { 0.0, 0.0, 0.0 };
  EXPECT_FALSE(core.setWrench(kRight, nan3, zero, 1.0));
  core.rejectWrench(kLeft);
  core.countSendError();
  const LinkHealth h = core.health(1.01);
  EXPECT_EQ(h.level, LinkLevel::OK);
  EXPECT_EQ(h.received, 1u);
  EXPECT_EQ(h.rejected[static_cast<int>(Reject::DUPLICATE)], 1u);
  EXPECT_EQ(h.rejected[static_cast<int>(Reject::MAC)], 1u);
  EXPECT_EQ(h.rejected[static_cast<int>(Reject::SIZE)], 1u);
  EXPECT_EQ(h.rejected[static_cast<int>(Reject::FOREIGN_SOURCE)], 1u);
  EXPECT_EQ(h.rejectedDatagrams(), 4u);
  EXPECT_EQ(h.wrench_rejected, 2u);
  EXPECT_EQ(h.send_errors, 1u);
  EXPECT_NEAR(h.input_age, 0.01, 1e-9);

  const HealthReport r = describeHealth(h, 987.65, "127.0.0.1:5005");
  const auto kv = asMap(r);
  EXPECT_EQ(r.level, LinkLevel::OK);
  EXPECT_EQ(r.message, "streaming");
  EXPECT_EQ(kv.at("packet rate [Hz]"), "987.6");
  EXPECT_EQ(kv.at("packets received"), "1");
  EXPECT_EQ(kv.at("input age [ms]"), "10.0");
  EXPECT_EQ(kv.at("timeout [ms]"), "30.0");
  EXPECT_EQ(kv.at("rejected datagrams"), "4");
  EXPECT_EQ(kv.at("rejected mac"), "1");
  EXPECT_EQ(kv.at("rejected duplicate"), "1");
  EXPECT_EQ(kv.at("rejected size"), "1");
  EXPECT_EQ(kv.at("rejected foreign_source"), "1");
  EXPECT_EQ(kv.at("rejected out_of_order"), "0");
  EXPECT_EQ(kv.at("rejected wrench_cmd"), "2");
  EXPECT_EQ(kv.at("command send errors"), "1");
  EXPECT_EQ(kv.at("sessions opened"), "1");
  EXPECT_EQ(kv.at("source"), "127.0.0.1:5005");
  for (int i = 0; i < kRejectReasons; ++i)
    EXPECT_EQ(kv.count(std::string("rejected ") + rejectName(static_cast<Reject>(i))), 1u) << i;
}

TEST(ReceiverCore, StatusTextAndStalledReceiveThread)
{
  ReceiverCore core(linkParams(), WrenchLimits(), touchball_test::testKey(), 3.0, testNonce);
  openSession(core);
  char text[160];
  LinkHealth h = core.health(0.0);
  EXPECT_EQ(h.level, LinkLevel::STALE);
  EXPECT_STREQ(formatStatusText(h, "*:5005", text, sizeof text), "no valid packet from *:5005 yet");
  EXPECT_EQ(asMap(describeHealth(h, 0.0, "*:5005")).at("input age [ms]"), "none received");
  AcceptedPacket out;
  bool resumed;
  const auto d = Builder(1, 1.0).done();
  core.accept(d.data(), d.size(), kLocal, 5.0, 0, out, resumed);
  // the receive thread has not run its watchdog (starved) for > 3 timeouts: STALE from the timer side
  h = core.health(5.1);
  EXPECT_TRUE(h.stalled);
  EXPECT_EQ(h.level, LinkLevel::STALE);
  EXPECT_STREQ(formatStatusText(h, "*:5005", text, sizeof text),
               "receive thread stalled: no packet handled for 100.0 ms");
  EXPECT_TRUE(core.watchdog(5.1));
  h = core.health(5.1);
  EXPECT_FALSE(h.stalled);
  EXPECT_EQ(h.level, LinkLevel::STALE);
  EXPECT_STREQ(formatStatusText(h, "127.0.0.1:5005", text, sizeof text),
               "no valid packet from 127.0.0.1:5005 for 100.0 ms (timeout 30 ms)");
}

TEST(ReceiverCore, PacketSinceReportsEachNewPacketOnce)
{
  ReceiverCore core(linkParams(), WrenchLimits(), touchball_test::testKey(), 3.0, testNonce);
  openSession(core);
  std::uint64_t seen = 0;
  StatePacket p;
  std::int64_t stamp = 0;
  EXPECT_FALSE(core.packetSince(seen, p, stamp));
  AcceptedPacket out;
  bool resumed;
  const auto d = Builder(4, 1.0).done();
  core.accept(d.data(), d.size(), kLocal, 1.0, 42, out, resumed);
  ASSERT_TRUE(core.packetSince(seen, p, stamp));
  EXPECT_EQ(p.seq, 4u);
  EXPECT_EQ(stamp, 42);
  EXPECT_FALSE(core.packetSince(seen, p, stamp));
}

TEST(ReceiverCore, ConcurrentWrenchUpdatesAndAccepts)
{
  // the callback queue sets commands while the receive thread accepts: every handed-out command is
  // one that was set (never torn), and nothing is lost from the counters
  ReceiverCore core(linkParams(), WrenchLimits{ 100.0, 0.0, 10.0 }, touchball_test::testKey(), 3.0, testNonce);
  openSession(core);
  std::atomic<bool> stop{ false };
  std::thread writer([&] {
    for (int k = 0; !stop; ++k)
    {
      const double f = static_cast<double>(k % 50), force[3] = { f, f, f }, torque[3] = { 0, 0, 0 };
      core.setWrench(kLeft, force, torque, 1.0);
    }
  });
  AcceptedPacket out;
  bool resumed;
  for (std::uint32_t s = 1; s <= 2000; ++s)
  {
    const auto d = Builder(s, 1.0 + 1e-3 * s).done();
    ASSERT_EQ(core.accept(d.data(), d.size(), kLocal, 1.0 + 1e-4 * s, 0, out, resumed), Reject::NONE);
    const double* f = out.commands[kLeft].force;
    EXPECT_TRUE(f[0] == f[1] && f[1] == f[2]) << s;
  }
  stop = true;
  writer.join();
  EXPECT_EQ(core.health(1.2).received, 2000u);
}

TEST(RateMeter, RateBetweenCalls)
{
  RateMeter m;
  EXPECT_EQ(m.update(100, 10.0), 0.0);
  EXPECT_DOUBLE_EQ(m.update(1100, 11.0), 1000.0);
  EXPECT_DOUBLE_EQ(m.update(1100, 13.0), 0.0);
  EXPECT_DOUBLE_EQ(m.update(1100, 13.0), 0.0);  // no time passed
}

/**
 * @file test_touchball_core.cpp
 * @brief Core tests of the C++ Touchball receiver (no roscore): protocol decode against packets
 *        built field by field here with OpenSSL's HMAC() (test vectors: test_touchball_auth.cpp),
 *        validation order, session handshake, sequence accounting,
 *        twist estimate, watchdog deadline, force latch. The other touchball gtests are linked into
 *        the same executable (test_touchball_kinematics.cpp, test_touchball_receiver_core.cpp,
 *        test_touchball_udp.cpp).
 */
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "saras_drivers/touchball_link.h"
#include "packet_builder.h"

using namespace saras_drivers::touchball;
using touchball_test::Builder;

void installOpenSslAllocationCounter();  // test_touchball_auth.cpp

namespace
{
LinkParams params()
{
  LinkParams p;
  p.source_ip = 0x7f000001;
  return p;
}
constexpr std::uint32_t kLocal = 0x7f000001;

std::uint64_t testNonce()
{
  return touchball_test::kSession;
}

/// A link keyed with the test key whose session (kSession) is open (hello answered at t = -1 s).
TouchballLink openLink(const LinkParams& p = params())
{
  TouchballLink link(p, touchball_test::testKey(), testNonce);
  const std::vector<std::uint8_t> h = touchball_test::hello();
  EXPECT_EQ(link.accept(h.data(), h.size(), p.source_ip, -1.0), Reject::NONE);
  EXPECT_EQ(link.kind(), Accepted::HELLO);
  EXPECT_EQ(link.session(), touchball_test::kSession);
  return link;
}
}  // namespace

TEST(TouchballProtocol, RejectsEachDefectWithItsReason)
{
  const Hmac mac(touchball_test::testKey());
  const std::uint64_t S = touchball_test::kSession;
  StatePacket p;
  const std::vector<std::uint8_t> good = Builder(1, 2.0).done();
  ASSERT_EQ(decodeState(good.data(), good.size(), mac, S, p), Reject::NONE);
  EXPECT_DOUBLE_EQ(p.devices[1].position[1], 0.02);
  EXPECT_EQ(p.session, S);
  // truncated at every length, and one byte too long
  for (std::size_t n = 0; n < good.size(); ++n)
    EXPECT_EQ(decodeState(good.data(), n, mac, S, p), Reject::SIZE) << n;
  std::vector<std::uint8_t> longer = good;
  longer.push_back(0);
  EXPECT_EQ(decodeState(longer.data(), longer.size(), mac, S, p), Reject::SIZE);
  EXPECT_EQ(decodeState(nullptr, kStateSize, mac, S, p), Reject::SIZE);
  auto with = [&](std::size_t off, std::uint8_t v, bool resign) {
    Builder b(1, 2.0);
    b.b[off] = v;
    std::vector<std::uint8_t> d = resign ? b.done() : Builder(1, 2.0).done();
    if (!resign)
      d[off] = v;
    return decodeState(d.data(), d.size(), mac, S, p);
  };
  EXPECT_EQ(with(0, 'X', true), Reject::MAGIC);
  EXPECT_EQ(with(4, 1, true), Reject::VERSION);  // version 1: refused, never parsed
  EXPECT_EQ(with(5, 2, true), Reject::TYPE);
  EXPECT_EQ(with(40, 0x55, false), Reject::MAC);  // payload change without a new tag
  const std::vector<std::uint8_t> other = Builder(1, 2.0).done(std::vector<std::uint8_t>(32, 7));
  EXPECT_EQ(decodeState(other.data(), other.size(), mac, S, p), Reject::MAC);  // valid tag, another key
  const std::vector<std::uint8_t> old = Builder(1, 2.0, S + 1).done();
  EXPECT_EQ(decodeState(old.data(), old.size(), mac, S, p), Reject::SESSION);  // another session
  EXPECT_EQ(decodeState(good.data(), good.size(), mac, 0, p), Reject::SESSION);  // no session yet
  // a flipped bit anywhere is never accepted
  for (std::size_t off = 0; off < kStateSize; ++off)
  {
    std::vector<std::uint8_t> d = good;
    d[off] ^= 0x10;
    EXPECT_NE(decodeState(d.data(), d.size(), mac, S, p), Reject::NONE) << off;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  auto field = [&](std::size_t off, double v) {
    const std::vector<std::uint8_t> d = Builder(1, 2.0).f64(off, v).done();
    return decodeState(d.data(), d.size(), mac, S, p);
  };
  EXPECT_EQ(field(12, nan), Reject::NON_FINITE);        // sender time
  EXPECT_EQ(field(28, nan), Reject::NON_FINITE);        // left x
  EXPECT_EQ(field(28 + 68 + 56, inf), Reject::NON_FINITE);  // right clip angle
  EXPECT_EQ(field(52 + 24, -inf), Reject::NON_FINITE);  // left qw
  EXPECT_EQ(field(52 + 24, 0.9), Reject::QUATERNION);   // |q| = 0.9
  EXPECT_EQ(field(52 + 24, 1e300), Reject::QUATERNION); // finite but overflowing norm
  EXPECT_EQ(field(52 + 24, 1.0005), Reject::NONE);      // inside the 1e-3 tolerance: re-normalised
  EXPECT_NEAR(p.devices[0].orientation[3], 1.0, 1e-15);
  // non_finite is checked over both devices before any quaternion (documented order)
  const std::vector<std::uint8_t> both = Builder(1, 2.0).f64(52 + 24, 0.5).f64(28 + 68, nan).done();
  EXPECT_EQ(decodeState(both.data(), both.size(), mac, S, p), Reject::NON_FINITE);
}

TEST(TouchballProtocol, RandomBytesNeverAccepted)
{
  const Hmac mac(touchball_test::testKey());
  std::mt19937 rng(7);
  StatePacket p;
  for (int k = 0; k < 2000; ++k)
  {
    std::vector<std::uint8_t> d(k % 3 == 0 ? kStateSize : rng() % 300);
    for (auto& x : d)
      x = static_cast<std::uint8_t>(rng());
    if (k % 2 == 0 && d.size() >= 28)
    {
      std::memcpy(d.data(), "TBAL\x02\x01", 6);
      std::memcpy(&d[20], &touchball_test::kSession, 8);
    }
    EXPECT_NE(decodeState(d.data(), d.size(), mac, touchball_test::kSession, p), Reject::NONE);
  }
}

TEST(TouchballLink, SessionHandshake)
{
  TouchballLink link(params(), touchball_test::testKey(), testNonce);
  std::vector<std::uint8_t> d = Builder(1, 1.0).done();
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 0.0), Reject::SESSION);  // no session yet
  std::vector<std::uint8_t> h = touchball_test::hello(7, std::vector<std::uint8_t>(32, 9));
  EXPECT_EQ(link.accept(h.data(), h.size(), kLocal, 0.0), Reject::MAC);  // hello under another key
  h = touchball_test::hello();
  ASSERT_EQ(link.accept(h.data(), h.size(), kLocal, 0.0), Reject::NONE);
  EXPECT_EQ(link.kind(), Accepted::HELLO);
  EXPECT_EQ(link.consoleNonce(), touchball_test::kConsoleNonce);
  EXPECT_EQ(link.sessions(), 1u);
  ASSERT_EQ(link.accept(h.data(), h.size(), kLocal, 0.05), Reject::NONE);  // challenge lost: same session
  EXPECT_EQ(link.sessions(), 1u);
  ASSERT_EQ(link.accept(d.data(), d.size(), kLocal, 0.1), Reject::NONE);
  EXPECT_EQ(link.kind(), Accepted::STATE);
  EXPECT_EQ(link.accept(h.data(), h.size(), kLocal, 0.2), Reject::SESSION);  // streaming: refused
  const std::vector<std::uint8_t> h2 = touchball_test::hello(99);
  EXPECT_EQ(link.accept(h2.data(), h2.size(), kLocal, 1.0), Reject::SESSION);  // second console
  // after resync_after (1 s) without a state packet a new hello opens a new session
  ASSERT_EQ(link.accept(h2.data(), h2.size(), kLocal, 1.2), Reject::NONE);
  EXPECT_EQ(link.sessions(), 2u);
  d = Builder(0, 5.0).done();  // the sequence restarts with the session
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 1.3), Reject::NONE);
  EXPECT_EQ(link.received(), 2u);
}

TEST(TouchballLink, SourceSequenceAndCounters)
{
  TouchballLink link = openLink();
  auto pkt = [](std::uint32_t seq, double t) { return Builder(seq, t).done(); };
  std::vector<std::uint8_t> d = pkt(10, 1.0);
  EXPECT_EQ(link.accept(d.data(), d.size(), 0x7f000002, 0.0), Reject::FOREIGN_SOURCE);
  EXPECT_FALSE(link.hasValid());
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 0.0), Reject::NONE);
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 0.001), Reject::DUPLICATE);
  d = pkt(13, 1.003);
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 0.002), Reject::NONE);
  EXPECT_EQ(link.lastGap(), 2u);
  EXPECT_EQ(link.gaps(), 2u);
  d = pkt(12, 1.002);
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 0.003), Reject::OUT_OF_ORDER);
  d = pkt(0, 1.0);
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 0.004), Reject::OUT_OF_ORDER);
  d.resize(20);
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 0.005), Reject::SIZE);
  EXPECT_EQ(link.received(), 2u);
  EXPECT_EQ(link.rejectedTotal(), 5u);
  EXPECT_EQ(link.rejected(Reject::OUT_OF_ORDER), 2u);
  EXPECT_EQ(link.rejectedSummary(), "foreign_source 1, size 1, duplicate 1, out_of_order 2");
  EXPECT_EQ(link.packet().seq, 13u);  // rejected packets never replace the accepted one

  // serial-number arithmetic across the 2^32 wrap
  TouchballLink wrap = openLink();
  d = pkt(0xFFFFFFFF, 1.0);
  EXPECT_EQ(wrap.accept(d.data(), d.size(), kLocal, 0.0), Reject::NONE);
  d = pkt(1, 1.002);
  EXPECT_EQ(wrap.accept(d.data(), d.size(), kLocal, 0.001), Reject::NONE);
  EXPECT_EQ(wrap.lastGap(), 1u);

  LinkParams any = params();
  any.any_source = true;
  TouchballLink open = openLink(any);
  d = pkt(1, 1.0);
  EXPECT_EQ(open.accept(d.data(), d.size(), 0x0a000001, 0.0), Reject::NONE);
}

TEST(TouchballLink, TwistFromSenderTimes)
{
  LinkParams p = params();
  p.twist_cutoff_hz = 0.0;  // unfiltered: exact finite differences
  TouchballLink link = openLink(p);
  const double w = 0.5, dt = 0.001;
  for (int k = 0; k < 5; ++k)
  {
    const double t = 100.0 + k * dt, a = w * t;
    // x moves at 0.2 m/s, the left device rotates about z at w
    std::vector<std::uint8_t> d =
        Builder(k, t).f64(28, -0.1 + 0.2 * k * dt).f64(52 + 16, std::sin(a / 2)).f64(52 + 24, std::cos(a / 2)).done();
    // arrival jitter must not matter: receive times are irregular
    ASSERT_EQ(link.accept(d.data(), d.size(), kLocal, 0.01 * k * k), Reject::NONE);
  }
  EXPECT_NEAR(link.twist(0).linear()[0], 0.2, 1e-9);
  EXPECT_NEAR(link.twist(0).angular()[2], w, 1e-9);
  EXPECT_NEAR(link.twist(0).angular()[0], 0.0, 1e-12);
  EXPECT_NEAR(link.twist(1).linear()[0], 0.0, 1e-12);

  // filtered: first-order response, converges to the true rate (100 Hz cut-off, 1 kHz, 0.1 s)
  TouchballLink filt = openLink();
  for (int k = 0; k < 100; ++k)
  {
    std::vector<std::uint8_t> d = Builder(k, 5.0 + k * dt).f64(28, -0.1 + 0.2 * k * dt).done();
    filt.accept(d.data(), d.size(), kLocal, k * dt);
  }
  EXPECT_NEAR(filt.twist(0).linear()[0], 0.2, 1e-6);
}

TEST(TouchballLink, WatchdogDeadline)
{
  TouchballLink link = openLink();  // timeout 30 ms
  EXPECT_TRUE(std::isinf(link.inputAge(5.0)));
  EXPECT_TRUE(link.isStale(5.0));
  EXPECT_DOUBLE_EQ(link.waitTime(5.0, true, 0.1), 0.1);  // nothing yet: idle wake-ups
  std::vector<std::uint8_t> d = Builder(1, 1.0).done();
  ASSERT_EQ(link.accept(d.data(), d.size(), kLocal, 10.0), Reject::NONE);
  EXPECT_FALSE(link.isStale(10.0));
  EXPECT_NEAR(link.waitTime(10.0, false, 0.1), 0.030, 1e-12);  // sleep exactly to the deadline
  EXPECT_NEAR(link.waitTime(10.02, false, 0.1), 0.010, 1e-12);
  EXPECT_FALSE(link.isStale(10.03));                           // at the deadline: not yet
  EXPECT_TRUE(link.isStale(10.0301));
  EXPECT_DOUBLE_EQ(link.waitTime(10.05, false, 0.1), 0.0);     // overdue: do not block
  EXPECT_DOUBLE_EQ(link.waitTime(10.05, true, 0.1), 0.1);      // declared: idle wake-ups
  // a rejected datagram does not move the deadline
  d = Builder(1, 1.0).done();
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 10.025), Reject::DUPLICATE);
  EXPECT_NEAR(link.waitTime(10.025, false, 0.1), 0.005, 1e-12);
  d = Builder(2, 1.001).done();
  ASSERT_EQ(link.accept(d.data(), d.size(), kLocal, 10.029), Reject::NONE);
  EXPECT_NEAR(link.waitTime(10.029, false, 0.1), 0.030, 1e-12);
}

TEST(TouchballLink, InvalidParametersThrow)
{
  LinkParams p = params();
  p.timeout = 0.0;
  EXPECT_THROW(TouchballLink(p, touchball_test::testKey()), std::invalid_argument);
  p = params();
  p.resync_after = 0.01;
  EXPECT_THROW(TouchballLink(p, touchball_test::testKey()), std::invalid_argument);
  p = params();
  p.timeout = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(TouchballLink(p, touchball_test::testKey()), std::invalid_argument);
  EXPECT_THROW(WrenchLatch(-1.0, 0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(WrenchLatch(1.0, 0.0, 0.0), std::invalid_argument);
}

TEST(WrenchLatch, ClampAgeAndNaN)
{
  WrenchLatch latch(3.0, 0.0, 0.1);
  EXPECT_FALSE(latch.get(0.0).enabled);  // never set: zero force
  const double f[3] = { 3.0, 4.0, 0.0 }, t[3] = { 0.1, 0.0, 0.0 };
  ASSERT_TRUE(latch.set(f, t, 1.0));
  DeviceCommand c = latch.get(1.05);
  EXPECT_TRUE(c.enabled);
  EXPECT_NEAR(c.force[0], 1.8, 1e-12);  // |f| = 5 N clamped to 3 N, direction kept
  EXPECT_NEAR(c.force[1], 2.4, 1e-12);
  EXPECT_DOUBLE_EQ(c.torque[0], 0.0);   // max_torque 0
  EXPECT_FALSE(latch.get(1.1001).enabled);  // older than 100 ms
  const double bad[3] = { 1.0, std::numeric_limits<double>::quiet_NaN(), 0.0 };
  ASSERT_TRUE(latch.set(f, t, 2.0));
  EXPECT_FALSE(latch.set(bad, t, 2.01));
  c = latch.get(2.02);
  EXPECT_FALSE(c.enabled);
  EXPECT_DOUBLE_EQ(c.force[0], 0.0);
}

int main(int argc, char** argv)
{
  installOpenSslAllocationCounter();
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

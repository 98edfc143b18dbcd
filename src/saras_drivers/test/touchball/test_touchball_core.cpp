/**
 * @file test_touchball_core.cpp
 * @brief Core tests of the C++ Touchball receiver (no roscore): protocol decode against packets
 *        encoded by independent paths (bytes produced by the Python reference encoder, and packets
 *        built field by field here with zlib's CRC), validation order, sequence/resync accounting,
 *        twist estimate, watchdog deadline, force latch. The other touchball gtests are linked into
 *        the same executable (test_touchball_kinematics.cpp, test_touchball_receiver_core.cpp,
 *        test_touchball_udp.cpp).
 */
#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "saras_drivers/touchball_link.h"
#include "packet_builder.h"

using namespace saras_drivers::touchball;
using touchball_test::Builder;

namespace
{
// saras_drivers.touchball_protocol.pack_state(0xFFFFFFFE, 1700000000.25, (left, right)) with
// left = ((-0.12, 0.01, 0.07), (0, 0, sin 0.25, cos 0.25), 0.3, clutch), right = ((0.1, -0.02, 0.05),
// (0.5, 0.5, 0.5, 0.5), 0.75, clip button): bytes printed by the Python reference encoder.
const std::vector<std::uint8_t> kPythonState = {
  0x54, 0x42, 0x41, 0x4c, 0x01, 0x01, 0x00, 0x00, 0xfe, 0xff, 0xff, 0xff, 0x00, 0x00, 0x10, 0x40, 0xfc, 0x54, 0xd9,
  0x41, 0xb8, 0x1e, 0x85, 0xeb, 0x51, 0xb8, 0xbe, 0xbf, 0x7b, 0x14, 0xae, 0x47, 0xe1, 0x7a, 0x84, 0x3f, 0xec, 0x51,
  0xb8, 0x1e, 0x85, 0xeb, 0xb1, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
  0x00, 0x00, 0x00, 0x77, 0x15, 0xf3, 0xd4, 0xee, 0xaa, 0xcf, 0x3f, 0xa1, 0xee, 0x7d, 0x9f, 0x54, 0x01, 0xef, 0x3f,
  0x33, 0x33, 0x33, 0x33, 0x33, 0x33, 0xd3, 0x3f, 0x01, 0x00, 0x00, 0x00, 0x9a, 0x99, 0x99, 0x99, 0x99, 0x99, 0xb9,
  0x3f, 0x7b, 0x14, 0xae, 0x47, 0xe1, 0x7a, 0x94, 0xbf, 0x9a, 0x99, 0x99, 0x99, 0x99, 0x99, 0xa9, 0x3f, 0x00, 0x00,
  0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00,
  0x00, 0xe0, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe8, 0x3f,
  0x02, 0x00, 0x00, 0x00, 0x1a, 0x93, 0x98, 0x62
};
// pack_command(7, 12.5, (DeviceCommand((1, -2, 0.5), (0, 0, 0), True), ZERO_COMMAND)) (Python)
const std::vector<std::uint8_t> kPythonCommand = {
  0x54, 0x42, 0x41, 0x4c, 0x01, 0x02, 0x00, 0x00, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x29,
  0x40, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf0, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xc0, 0x00, 0x00,
  0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
  0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
  0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
  0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
  0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x2c, 0x25, 0xcf, 0xee
};

LinkParams params()
{
  LinkParams p;
  p.source_ip = 0x7f000001;
  return p;
}
constexpr std::uint32_t kLocal = 0x7f000001;
}  // namespace

TEST(TouchballProtocol, DecodesPythonEncodedPacket)
{
  StatePacket p;
  ASSERT_EQ(decodeState(kPythonState.data(), kPythonState.size(), p), Reject::NONE);
  EXPECT_EQ(p.seq, 0xFFFFFFFEu);
  EXPECT_DOUBLE_EQ(p.sender_time, 1700000000.25);
  const DeviceState& l = p.devices[0];
  EXPECT_DOUBLE_EQ(l.position[0], -0.12);
  EXPECT_DOUBLE_EQ(l.position[1], 0.01);
  EXPECT_DOUBLE_EQ(l.position[2], 0.07);
  EXPECT_NEAR(l.orientation[2], std::sin(0.25), 1e-15);
  EXPECT_NEAR(l.orientation[3], std::cos(0.25), 1e-15);
  EXPECT_DOUBLE_EQ(l.clip_angle, 0.3);
  EXPECT_TRUE(l.clutch());
  EXPECT_FALSE(l.clipButton());
  const DeviceState& r = p.devices[1];
  EXPECT_DOUBLE_EQ(r.position[0], 0.1);
  EXPECT_DOUBLE_EQ(r.position[1], -0.02);
  for (int i = 0; i < 4; ++i)
    EXPECT_DOUBLE_EQ(r.orientation[i], 0.5);
  EXPECT_DOUBLE_EQ(r.clip_angle, 0.75);
  EXPECT_FALSE(r.clutch());
  EXPECT_TRUE(r.clipButton());
}

TEST(TouchballProtocol, CrcMatchesStandardCheckValue)
{
  const char* s = "123456789";
  EXPECT_EQ(crc32(reinterpret_cast<const std::uint8_t*>(s), 9), 0xCBF43926u);
}

TEST(TouchballProtocol, EncodesCommandLikePython)
{
  std::array<DeviceCommand, 2> c;
  c[0].force[0] = 1.0;
  c[0].force[1] = -2.0;
  c[0].force[2] = 0.5;
  c[0].enabled = true;
  std::vector<std::uint8_t> out(kCommandSize);
  encodeCommand(7, 12.5, c, out.data());
  EXPECT_EQ(out, kPythonCommand);
}

TEST(TouchballProtocol, RejectsEachDefectWithItsReason)
{
  StatePacket p;
  const std::vector<std::uint8_t> good = Builder(1, 2.0).done();
  ASSERT_EQ(decodeState(good.data(), good.size(), p), Reject::NONE);
  EXPECT_DOUBLE_EQ(p.devices[1].position[1], 0.02);
  // truncated at every length, and one byte too long
  for (std::size_t n = 0; n < good.size(); ++n)
    EXPECT_EQ(decodeState(good.data(), n, p), Reject::SIZE) << n;
  std::vector<std::uint8_t> longer = good;
  longer.push_back(0);
  EXPECT_EQ(decodeState(longer.data(), longer.size(), p), Reject::SIZE);
  EXPECT_EQ(decodeState(nullptr, 160, p), Reject::SIZE);
  auto with = [&](std::size_t off, std::uint8_t v, bool fix_crc) {
    Builder b(1, 2.0);
    b.b[off] = v;
    std::vector<std::uint8_t> d = fix_crc ? b.done() : Builder(1, 2.0).done();
    if (!fix_crc)
      d[off] = v;
    return decodeState(d.data(), d.size(), p);
  };
  EXPECT_EQ(with(0, 'X', true), Reject::MAGIC);
  EXPECT_EQ(with(4, 2, true), Reject::VERSION);
  EXPECT_EQ(with(5, 2, true), Reject::TYPE);
  EXPECT_EQ(with(30, 0x55, false), Reject::CRC);  // payload bit flips without a new CRC
  // a flipped bit anywhere is never accepted
  for (std::size_t off = 0; off < 160; ++off)
  {
    std::vector<std::uint8_t> d = good;
    d[off] ^= 0x10;
    EXPECT_NE(decodeState(d.data(), d.size(), p), Reject::NONE) << off;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  auto field = [&](std::size_t off, double v) {
    const std::vector<std::uint8_t> d = Builder(1, 2.0).f64(off, v).done();
    return decodeState(d.data(), d.size(), p);
  };
  EXPECT_EQ(field(12, nan), Reject::NON_FINITE);        // sender time
  EXPECT_EQ(field(20, nan), Reject::NON_FINITE);        // left x
  EXPECT_EQ(field(20 + 68 + 56, inf), Reject::NON_FINITE);  // right clip angle
  EXPECT_EQ(field(44 + 24, -inf), Reject::NON_FINITE);  // left qw
  EXPECT_EQ(field(44 + 24, 0.9), Reject::QUATERNION);   // |q| = 0.9
  EXPECT_EQ(field(44 + 24, 1e300), Reject::QUATERNION); // finite but overflowing norm
  EXPECT_EQ(field(44 + 24, 1.0005), Reject::NONE);      // inside the 1e-3 tolerance: re-normalised
  EXPECT_NEAR(p.devices[0].orientation[3], 1.0, 1e-15);
  // non_finite is checked over both devices before any quaternion (documented order)
  const std::vector<std::uint8_t> both = Builder(1, 2.0).f64(44 + 24, 0.5).f64(20 + 68, nan).done();
  EXPECT_EQ(decodeState(both.data(), both.size(), p), Reject::NON_FINITE);
}

TEST(TouchballProtocol, RandomBytesNeverAccepted)
{
  std::mt19937 rng(7);
  StatePacket p;
  for (int k = 0; k < 2000; ++k)
  {
    std::vector<std::uint8_t> d(k % 3 == 0 ? 160 : rng() % 300);
    for (auto& x : d)
      x = static_cast<std::uint8_t>(rng());
    if (k % 2 == 0 && d.size() >= 6)
      std::memcpy(d.data(), "TBAL\x01\x01", 6);
    EXPECT_NE(decodeState(d.data(), d.size(), p), Reject::NONE);
  }
}

TEST(TouchballLink, SourceSequenceAndCounters)
{
  TouchballLink link(params());
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
  TouchballLink wrap(params());
  d = pkt(0xFFFFFFFF, 1.0);
  EXPECT_EQ(wrap.accept(d.data(), d.size(), kLocal, 0.0), Reject::NONE);
  d = pkt(1, 1.002);
  EXPECT_EQ(wrap.accept(d.data(), d.size(), kLocal, 0.001), Reject::NONE);
  EXPECT_EQ(wrap.lastGap(), 1u);

  LinkParams any = params();
  any.any_source = true;
  TouchballLink open(any);
  d = pkt(1, 1.0);
  EXPECT_EQ(open.accept(d.data(), d.size(), 0x0a000001, 0.0), Reject::NONE);
}

TEST(TouchballLink, ResyncOnlyWithNewerSenderTime)
{
  TouchballLink link(params());  // resync_after 1 s
  std::vector<std::uint8_t> d = Builder(500, 10.0).done();
  ASSERT_EQ(link.accept(d.data(), d.size(), kLocal, 0.0), Reject::NONE);
  d = Builder(0, 11.0).done();  // console restarted within resync_after: still out of order
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 0.5), Reject::OUT_OF_ORDER);
  d = Builder(3, 9.0).done();  // after the silence, but an old packet replayed
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 2.0), Reject::OUT_OF_ORDER);
  d = Builder(0, 11.0).done();  // restarted console: accepted
  EXPECT_EQ(link.accept(d.data(), d.size(), kLocal, 2.1), Reject::NONE);
  EXPECT_EQ(link.packet().seq, 0u);
  EXPECT_EQ(link.lastGap(), 0u);
}

TEST(TouchballLink, TwistFromSenderTimes)
{
  LinkParams p = params();
  p.twist_cutoff_hz = 0.0;  // unfiltered: exact finite differences
  TouchballLink link(p);
  const double w = 0.5, dt = 0.001;
  for (int k = 0; k < 5; ++k)
  {
    const double t = 100.0 + k * dt, a = w * t;
    // x moves at 0.2 m/s, the left device rotates about z at w
    std::vector<std::uint8_t> d =
        Builder(k, t).f64(20, -0.1 + 0.2 * k * dt).f64(44 + 16, std::sin(a / 2)).f64(44 + 24, std::cos(a / 2)).done();
    // arrival jitter must not matter: receive times are irregular
    ASSERT_EQ(link.accept(d.data(), d.size(), kLocal, 0.01 * k * k), Reject::NONE);
  }
  EXPECT_NEAR(link.twist(0).linear()[0], 0.2, 1e-9);
  EXPECT_NEAR(link.twist(0).angular()[2], w, 1e-9);
  EXPECT_NEAR(link.twist(0).angular()[0], 0.0, 1e-12);
  EXPECT_NEAR(link.twist(1).linear()[0], 0.0, 1e-12);

  // filtered: first-order response, converges to the true rate (100 Hz cut-off, 1 kHz, 0.1 s)
  TouchballLink filt(params());
  for (int k = 0; k < 100; ++k)
  {
    std::vector<std::uint8_t> d = Builder(k, 5.0 + k * dt).f64(20, -0.1 + 0.2 * k * dt).done();
    filt.accept(d.data(), d.size(), kLocal, k * dt);
  }
  EXPECT_NEAR(filt.twist(0).linear()[0], 0.2, 1e-6);
}

TEST(TouchballLink, WatchdogDeadline)
{
  TouchballLink link(params());  // timeout 30 ms
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
  EXPECT_THROW(TouchballLink{ p }, std::invalid_argument);
  p = params();
  p.resync_after = 0.01;
  EXPECT_THROW(TouchballLink{ p }, std::invalid_argument);
  p = params();
  p.timeout = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(TouchballLink{ p }, std::invalid_argument);
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
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

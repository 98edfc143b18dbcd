/**
 * @file packet_builder.h
 * @brief Test-side encoder of Touchball state packets, independent of the decoder under test
 *        (little-endian host assumed, as on every ROS target; CRC from zlib).
 */
#ifndef SARAS_DRIVERS_TEST_TOUCHBALL_PACKET_BUILDER_H
#define SARAS_DRIVERS_TEST_TOUCHBALL_PACKET_BUILDER_H

#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <vector>

namespace touchball_test
{
/// A valid state packet (both devices at rest, identity orientation) to modify field by field.
struct Builder
{
  std::vector<std::uint8_t> b = std::vector<std::uint8_t>(160, 0);
  Builder(std::uint32_t seq, double t)
  {
    std::memcpy(b.data(), "TBAL", 4);
    b[4] = 1;
    b[5] = 1;
    std::memcpy(&b[8], &seq, 4);
    std::memcpy(&b[12], &t, 8);
    for (int d = 0; d < 2; ++d)
    {
      const double pos[3] = { -0.1, 0.02 * d, 0.08 }, q[4] = { 0, 0, 0, 1 };
      std::memcpy(&b[20 + 68 * d], pos, 24);
      std::memcpy(&b[44 + 68 * d], q, 32);
    }
  }
  Builder& f64(std::size_t off, double v)
  {
    std::memcpy(&b[off], &v, 8);
    return *this;
  }
  std::vector<std::uint8_t> done()
  {
    const std::uint32_t c = static_cast<std::uint32_t>(::crc32(0L, b.data(), 156));
    std::memcpy(&b[156], &c, 4);
    return b;
  }
};

}  // namespace touchball_test

#endif  // SARAS_DRIVERS_TEST_TOUCHBALL_PACKET_BUILDER_H

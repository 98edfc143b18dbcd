/**
 * @file touchball_protocol.cpp
 * @brief Touchball UDP protocol v1: state packet decoding/validation, command packet encoding.
 */
#include "saras_drivers/touchball_protocol.h"

#include <cmath>
#include <cstring>

#include <zlib.h>

namespace saras_drivers
{
namespace touchball
{
const char* const kDeviceNames[kDevices] = { "left", "right" };

namespace
{
const char* const kRejectNames[kRejectReasons] = { "foreign_source", "size", "magic", "version", "type", "crc",
                                                   "non_finite", "quaternion", "duplicate", "out_of_order" };

std::uint32_t loadU32(const std::uint8_t* p)
{
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

double loadF64(const std::uint8_t* p)
{
  std::uint64_t u = 0;
  for (int i = 7; i >= 0; --i)
    u = (u << 8) | p[i];
  double d;
  std::memcpy(&d, &u, sizeof d);
  return d;
}

void storeU32(std::uint32_t v, std::uint8_t* p)
{
  for (int i = 0; i < 4; ++i)
    p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

void storeF64(double d, std::uint8_t* p)
{
  std::uint64_t u;
  std::memcpy(&u, &d, sizeof u);
  for (int i = 0; i < 8; ++i)
    p[i] = static_cast<std::uint8_t>(u >> (8 * i));
}

void storeHeader(std::uint8_t type, std::uint32_t seq, double sender_time, std::uint8_t* p)
{
  p[0] = 'T';
  p[1] = 'B';
  p[2] = 'A';
  p[3] = 'L';
  p[4] = kVersion;
  p[5] = type;
  p[6] = p[7] = 0;  // flags
  storeU32(seq, p + 8);
  storeF64(sender_time, p + 12);
}
}  // namespace

const char* rejectName(Reject r)
{
  const int i = static_cast<int>(r);
  return i >= 0 && i < kRejectReasons ? kRejectNames[i] : "none";
}

std::uint32_t crc32(const std::uint8_t* data, std::size_t n)
{
  return static_cast<std::uint32_t>(::crc32(::crc32(0L, Z_NULL, 0), data, static_cast<uInt>(n)));
}

Reject decodeState(const std::uint8_t* data, std::size_t n, StatePacket& out)
{
  if (data == nullptr || n != kStateSize)
    return Reject::SIZE;
  if (std::memcmp(data, "TBAL", 4) != 0)
    return Reject::MAGIC;
  if (data[4] != kVersion)
    return Reject::VERSION;
  if (data[5] != kTypeState)
    return Reject::TYPE;
  if (loadU32(data + kStateSize - 4) != crc32(data, kStateSize - 4))
    return Reject::CRC;
  out.seq = loadU32(data + 8);
  out.sender_time = loadF64(data + 12);
  if (!std::isfinite(out.sender_time))
    return Reject::NON_FINITE;
  for (int d = 0; d < kDevices; ++d)  // every float of both devices before any quaternion check
  {
    const std::uint8_t* p = data + kHeaderSize + d * kStateDeviceSize;
    DeviceState& s = out.devices[d];
    bool finite = true;
    for (int i = 0; i < 3; ++i)
      finite &= std::isfinite(s.position[i] = loadF64(p + 8 * i));
    for (int i = 0; i < 4; ++i)
      finite &= std::isfinite(s.orientation[i] = loadF64(p + 24 + 8 * i));
    finite &= std::isfinite(s.clip_angle = loadF64(p + 56));
    s.buttons = loadU32(p + 64);
    if (!finite)
      return Reject::NON_FINITE;
  }
  for (int d = 0; d < kDevices; ++d)
  {
    double* q = out.devices[d].orientation;
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(std::fabs(norm - 1.0) <= kQuaternionNormTolerance))  // also catches an overflowing norm
      return Reject::QUATERNION;
    for (int i = 0; i < 4; ++i)
      q[i] /= norm;
  }
  return Reject::NONE;
}

void encodeCommand(std::uint32_t seq, double sender_time, const std::array<DeviceCommand, kDevices>& commands,
                   std::uint8_t* out)
{
  storeHeader(kTypeCommand, seq, sender_time, out);
  for (int d = 0; d < kDevices; ++d)
  {
    std::uint8_t* p = out + kHeaderSize + d * kCommandDeviceSize;
    const DeviceCommand& c = commands[d];
    for (int i = 0; i < 3; ++i)
    {
      storeF64(c.force[i], p + 8 * i);
      storeF64(c.torque[i], p + 24 + 8 * i);
    }
    storeU32(c.enabled ? kCommandEnabled : 0u, p + 48);
  }
  storeU32(crc32(out, kCommandSize - 4), out + kCommandSize - 4);
}

}  // namespace touchball
}  // namespace saras_drivers

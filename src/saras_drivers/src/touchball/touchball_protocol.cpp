/**
 * @file touchball_protocol.cpp
 * @brief Touchball UDP protocol v2: frame and tag check, state / hello decoding and validation,
 *        command / challenge encoding.
 */
#include "saras_drivers/touchball_protocol.h"

#include <cmath>
#include <cstring>

namespace saras_drivers
{
namespace touchball
{
const char* const kDeviceNames[kDevices] = { "left", "right" };

namespace
{
const char* const kRejectNames[kRejectReasons] = { "foreign_source", "size", "magic", "version", "type", "mac", "session",
                                                   "non_finite", "quaternion", "duplicate", "out_of_order" };

const char* const kRejectHelp[kRejectReasons] = {
  "source address is not ~allowed_source",
  "wrong datagram size for its type",
  "not a Touchball packet (magic)",
  "protocol version not 2 (version 1 is unauthenticated and refused: update the console to version 2, "
  "docs/touchball_protocol.md)",
  "packet type not STATE or HELLO",
  "authentication tag invalid (forged, corrupted, or another key: check the key files of both sides)",
  "not bound to the current session (old/other session, or a hello while a session streams)",
  "non-finite field",
  "quaternion norm not 1",
  "duplicate sequence number (replay)",
  "sequence number older than the last accepted one (replay or reordering)"
};

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

std::uint64_t loadU64(const std::uint8_t* p)
{
  std::uint64_t u = 0;
  for (int i = 7; i >= 0; --i)
    u = (u << 8) | p[i];
  return u;
}

void storeU64(std::uint64_t v, std::uint8_t* p)
{
  for (int i = 0; i < 8; ++i)
    p[i] = static_cast<std::uint8_t>(v >> (8 * i));
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

void storeHeader(std::uint8_t type, std::uint32_t seq, double sender_time, std::uint64_t session, std::uint8_t* p)
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
  storeU64(session, p + 20);
}
}  // namespace

const char* rejectHelp(Reject r)
{
  const int i = static_cast<int>(r);
  return i >= 0 && i < kRejectReasons ? kRejectHelp[i] : "";
}

const char* rejectName(Reject r)
{
  const int i = static_cast<int>(r);
  return i >= 0 && i < kRejectReasons ? kRejectNames[i] : "none";
}

Reject checkFrame(const std::uint8_t* data, std::size_t n, const Hmac& mac, std::uint8_t& type)
{
  if (data == nullptr || n < 6)
    return Reject::SIZE;
  if (std::memcmp(data, "TBAL", 4) != 0)
    return Reject::MAGIC;
  if (data[4] != kVersion)  // v1 (unauthenticated) or unknown: never parsed further
    return Reject::VERSION;
  type = data[5];
  if (type != kTypeState && type != kTypeHello)
    return Reject::TYPE;
  if (n != (type == kTypeState ? kStateSize : kHelloSize))
    return Reject::SIZE;
  if (!mac.verify(data, n - kTagSize, data + n - kTagSize))
    return Reject::MAC;
  return Reject::NONE;
}

Reject decodeState(const std::uint8_t* data, std::uint64_t session, StatePacket& out)
{
  out.session = loadU64(data + 20);
  if (session == 0 || out.session != session)
    return Reject::SESSION;
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

Reject decodeHello(const std::uint8_t* data, Hello& out)
{
  out.seq = loadU32(data + 8);
  out.sender_time = loadF64(data + 12);
  out.console_nonce = loadU64(data + 20);
  if (out.console_nonce == 0 || !std::isfinite(out.sender_time))
    return Reject::SESSION;
  return Reject::NONE;
}

Reject decodeState(const std::uint8_t* data, std::size_t n, const Hmac& mac, std::uint64_t session, StatePacket& out)
{
  std::uint8_t type = 0;
  const Reject r = checkFrame(data, n, mac, type);
  if (r != Reject::NONE)
    return r;
  return type == kTypeState ? decodeState(data, session, out) : Reject::TYPE;
}

void encodeCommand(std::uint32_t seq, double sender_time, std::uint64_t session,
                   const std::array<DeviceCommand, kDevices>& commands, const Hmac& mac, std::uint8_t* out)
{
  storeHeader(kTypeCommand, seq, sender_time, session, out);
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
  mac.tag(out, kCommandSize - kTagSize, out + kCommandSize - kTagSize);
}

void encodeChallenge(std::uint32_t seq, double sender_time, std::uint64_t session, std::uint64_t console_nonce,
                     const Hmac& mac, std::uint8_t* out)
{
  storeHeader(kTypeChallenge, seq, sender_time, session, out);
  storeU64(console_nonce, out + kHeaderSize);
  mac.tag(out, kChallengeSize - kTagSize, out + kChallengeSize - kTagSize);
}

}  // namespace touchball
}  // namespace saras_drivers

/**
 * @file touchball_protocol.h
 * @brief Touchball console link, UDP protocol version 2 (docs/touchball_protocol.md): authenticated
 *        packets (HMAC-SHA256 tag, session nonce, sequence). Decoding and validation of the 180-byte
 *        state and 44-byte hello packets, encoding of the 148-byte command and 52-byte challenge.
 *
 * ROS-agnostic, allocation-free. All fields little-endian, floats IEEE-754 binary64; the byte
 * order is handled explicitly so the code is correct on any host. The Python module
 * saras_drivers.touchball_protocol is the reference encoder (console simulator, tests).
 * Units: m, unit quaternion (x, y, z, w), rad, s, N, N m.
 */
#ifndef SARAS_DRIVERS_TOUCHBALL_PROTOCOL_H
#define SARAS_DRIVERS_TOUCHBALL_PROTOCOL_H

#include <array>
#include <cstddef>
#include <cstdint>

#include "saras_drivers/touchball_auth.h"

namespace saras_drivers
{
namespace touchball
{
constexpr std::uint8_t kVersion = 2;
constexpr std::uint8_t kTypeState = 1;      ///< console -> ROS, device states
constexpr std::uint8_t kTypeCommand = 2;    ///< ROS -> console, force commands
constexpr std::uint8_t kTypeHello = 3;      ///< console -> ROS, asks for a session
constexpr std::uint8_t kTypeChallenge = 4;  ///< ROS -> console, the session nonce
constexpr std::size_t kHeaderSize = 28;        ///< magic, version, type, flags, seq, sender_time, session
constexpr std::size_t kStateDeviceSize = 68;   ///< 3 f64 position, 4 f64 quaternion, f64 clip, u32 buttons
constexpr std::size_t kCommandDeviceSize = 52; ///< 3 f64 force, 3 f64 torque, u32 flags
constexpr std::size_t kStateSize = kHeaderSize + 2 * kStateDeviceSize + kTagSize;      ///< 180 bytes
constexpr std::size_t kCommandSize = kHeaderSize + 2 * kCommandDeviceSize + kTagSize;  ///< 148 bytes
constexpr std::size_t kHelloSize = kHeaderSize + kTagSize;                             ///< 44 bytes
constexpr std::size_t kChallengeSize = kHeaderSize + 8 + kTagSize;                     ///< 52 bytes
constexpr std::uint32_t kButtonClutch = 0x1;
constexpr std::uint32_t kButtonClip = 0x2;
constexpr std::uint32_t kCommandEnabled = 0x1;
/// Accepted deviation of the quaternion norm from 1 before a packet is rejected.
constexpr double kQuaternionNormTolerance = 1e-3;
constexpr int kLeft = 0, kRight = 1, kDevices = 2;
/// Device (side) names in packet order.
extern const char* const kDeviceNames[kDevices];

/// Why a datagram was rejected; every rejection is counted under exactly one reason (wire order).
enum class Reject : int
{
  NONE = -1,
  FOREIGN_SOURCE = 0,
  SIZE,
  MAGIC,
  VERSION,
  TYPE,
  MAC,
  SESSION,
  NON_FINITE,
  QUATERNION,
  DUPLICATE,
  OUT_OF_ORDER,
  COUNT
};
constexpr int kRejectReasons = static_cast<int>(Reject::COUNT);
/// Reason name as used in the status message and the Python module ("foreign_source", "mac", ...).
const char* rejectName(Reject r);
/// One-line explanation of a reason for the log ("protocol version 1 (unauthenticated) refused: ...").
const char* rejectHelp(Reject r);

/// One device of a state packet.
struct DeviceState
{
  double position[3] = { 0.0, 0.0, 0.0 };           ///< [m] in touch_<side>/base
  double orientation[4] = { 0.0, 0.0, 0.0, 1.0 };   ///< unit quaternion (x, y, z, w), re-normalised
  double clip_angle = 0.0;                          ///< [rad]
  std::uint32_t buttons = 0;                        ///< bit mask (kButtonClutch, kButtonClip)
  bool clutch() const { return (buttons & kButtonClutch) != 0; }
  bool clipButton() const { return (buttons & kButtonClip) != 0; }
};

/// A decoded state packet.
struct StatePacket
{
  std::uint32_t seq = 0;
  double sender_time = 0.0;   ///< console wall clock [s]
  std::uint64_t session = 0;  ///< session nonce the packet is bound to
  std::array<DeviceState, kDevices> devices;
};

/// Force command of one device (touch_<side>/base).
struct DeviceCommand
{
  double force[3] = { 0.0, 0.0, 0.0 };   ///< [N]
  double torque[3] = { 0.0, 0.0, 0.0 };  ///< [N m]
  bool enabled = false;                  ///< false: the console applies zero force
};

/// Header fields of a hello packet (console -> ROS).
struct Hello
{
  std::uint32_t seq = 0;
  double sender_time = 0.0;
  std::uint64_t console_nonce = 0;  ///< the console's random nonce (echoed by the challenge)
};

/**
 * Check the frame of a datagram and return its type: size (>= 6 bytes), magic, version (a v1
 * packet => VERSION), type (STATE or HELLO), exact size of that type, tag. On Reject::NONE
 * @p type is kTypeState or kTypeHello. Never reads beyond @p n bytes.
 */
Reject checkFrame(const std::uint8_t* data, std::size_t n, const Hmac& mac, std::uint8_t& type);

/**
 * Decode and validate a state packet whose frame checkFrame() accepted. Checks in the documented
 * order: session (must equal @p session, non-zero), non_finite (sender time, then every float of
 * the left, then the right device), quaternion (left, then right). Returns Reject::NONE and fills
 * @p out on success (quaternions re-normalised); on failure @p out is unspecified.
 */
Reject decodeState(const std::uint8_t* data, std::uint64_t session, StatePacket& out);

/// Decode a hello packet whose frame checkFrame() accepted (SESSION if its nonce is 0 or the time not finite).
Reject decodeHello(const std::uint8_t* data, Hello& out);

/// checkFrame + decodeState for a datagram that must be a state packet (TYPE if it is a hello).
Reject decodeState(const std::uint8_t* data, std::size_t n, const Hmac& mac, std::uint64_t session,
                   StatePacket& out);

/// Encode a command packet into @p out (kCommandSize bytes), bound to @p session and tagged.
void encodeCommand(std::uint32_t seq, double sender_time, std::uint64_t session,
                   const std::array<DeviceCommand, kDevices>& commands, const Hmac& mac, std::uint8_t* out);

/// Encode a challenge (kChallengeSize bytes): the new @p session for the hello of @p console_nonce.
void encodeChallenge(std::uint32_t seq, double sender_time, std::uint64_t session, std::uint64_t console_nonce,
                     const Hmac& mac, std::uint8_t* out);

}  // namespace touchball
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_TOUCHBALL_PROTOCOL_H

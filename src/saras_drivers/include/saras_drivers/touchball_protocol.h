/**
 * @file touchball_protocol.h
 * @brief Touchball console link, UDP protocol version 1 (docs/touchball_protocol.md): decoding and
 *        validation of the 160-byte state packet, encoding of the 128-byte command packet.
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

namespace saras_drivers
{
namespace touchball
{
constexpr std::uint8_t kVersion = 1;
constexpr std::uint8_t kTypeState = 1;
constexpr std::uint8_t kTypeCommand = 2;
constexpr std::size_t kHeaderSize = 20;        ///< magic, version, type, flags, seq, sender_time
constexpr std::size_t kStateDeviceSize = 68;   ///< 3 f64 position, 4 f64 quaternion, f64 clip, u32 buttons
constexpr std::size_t kCommandDeviceSize = 52; ///< 3 f64 force, 3 f64 torque, u32 flags
constexpr std::size_t kStateSize = kHeaderSize + 2 * kStateDeviceSize + 4;     ///< 160 bytes
constexpr std::size_t kCommandSize = kHeaderSize + 2 * kCommandDeviceSize + 4; ///< 128 bytes
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
  CRC,
  NON_FINITE,
  QUATERNION,
  DUPLICATE,
  OUT_OF_ORDER,
  COUNT
};
constexpr int kRejectReasons = static_cast<int>(Reject::COUNT);
/// Reason name as used in the status message and the Python module ("foreign_source", "crc", ...).
const char* rejectName(Reject r);

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
  double sender_time = 0.0;  ///< console wall clock [s]
  std::array<DeviceState, kDevices> devices;
};

/// Force command of one device (touch_<side>/base).
struct DeviceCommand
{
  double force[3] = { 0.0, 0.0, 0.0 };   ///< [N]
  double torque[3] = { 0.0, 0.0, 0.0 };  ///< [N m]
  bool enabled = false;                  ///< false: the console applies zero force
};

/// CRC-32 (IEEE 802.3, as zlib.crc32) of n bytes.
std::uint32_t crc32(const std::uint8_t* data, std::size_t n);

/**
 * Decode and validate a state packet. Checks in the documented order: size, magic, version,
 * type, crc, non_finite (sender time, then every float of the left, then the right device),
 * quaternion (left, then right). Returns Reject::NONE and fills @p out on success (quaternions
 * re-normalised); on failure @p out is unspecified. Never reads beyond @p n bytes.
 */
Reject decodeState(const std::uint8_t* data, std::size_t n, StatePacket& out);

/// Encode a command packet into @p out (kCommandSize bytes). Disabled devices are sent as given.
void encodeCommand(std::uint32_t seq, double sender_time, const std::array<DeviceCommand, kDevices>& commands,
                   std::uint8_t* out);

}  // namespace touchball
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_TOUCHBALL_PROTOCOL_H

/**
 * @file touchball_link.h
 * @brief Touchball receiver core (ROS-agnostic): source filter, packet authentication and
 *        validation, session handshake, sequence accounting, twist estimation, watchdog deadline,
 *        force command latch.
 *
 * The nodelet saras_drivers/TouchballReceiver owns the socket, the thread and the publishers;
 * everything that decides whether a datagram is accepted, what is published and when the link
 * is stale lives here and is unit-tested without ROS (test/touchball/). Times ("now") are any
 * monotonic clock [s]; units m, rad, s, N, N m.
 */
#ifndef SARAS_DRIVERS_TOUCHBALL_LINK_H
#define SARAS_DRIVERS_TOUCHBALL_LINK_H

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "saras_drivers/touchball_protocol.h"

namespace saras_drivers
{
namespace touchball
{
/**
 * Accepts strictly increasing 32-bit sequence numbers (serial-number arithmetic, RFC 1982).
 */
class SequenceTracker
{
public:
  /// Reject::NONE and the number of missing packets before @p seq in @p gap, or DUPLICATE /
  /// OUT_OF_ORDER (state unchanged).
  Reject accept(std::uint32_t seq, std::uint32_t& gap);
  /// Forget the last number: the next packet is accepted whatever its value.
  void reset() { has_last_ = false; }
  std::uint64_t gaps() const { return gaps_; }

private:
  bool has_last_ = false;
  std::uint32_t last_ = 0;
  std::uint64_t gaps_ = 0;
};

/**
 * Finite-difference twist of a pose stream, first-order low-pass filtered (cut-off @p cutoff_hz,
 * <= 0: none). Differences use the sender timestamps. Angular velocity in the base frame:
 * w = log(q_k q_{k-1}^-1) / dt. A step dt <= 0 or > @p max_dt [s] restarts it (twist 0).
 */
class TwistEstimator
{
public:
  explicit TwistEstimator(double cutoff_hz = 100.0, double max_dt = 0.1);
  void reset();
  /// Feed a sample (sender time [s], position [m], unit quaternion x, y, z, w).
  void update(double t, const double p[3], const double q[4]);
  const double* linear() const { return linear_; }    ///< [m/s]
  const double* angular() const { return angular_; }  ///< [rad/s]

private:
  double tau_, max_dt_;
  bool has_prev_ = false;
  double t_ = 0.0, p_[3] = { 0, 0, 0 }, q_[4] = { 0, 0, 0, 1 };
  double linear_[3] = { 0, 0, 0 }, angular_[3] = { 0, 0, 0 };
};

/// Parameters of a link (validated by TouchballLink's constructor).
struct LinkParams
{
  bool any_source = false;         ///< accept every source address
  std::uint32_t source_ip = 0;     ///< allowed IPv4 source, host byte order (127.0.0.1 = 0x7f000001)
  double timeout = 0.03;           ///< [s] watchdog: no valid packet for this long => stale
  double resync_after = 1.0;       ///< [s] no state packet in the session for this long: a hello opens a new one (>= timeout)
  double twist_cutoff_hz = 100.0;  ///< [Hz] twist low-pass cut-off (0 = none)
};

/// Source of session nonces (non-zero, unpredictable); randomNonce() on the platform.
using NonceSource = std::uint64_t (*)();

/// What the last accepted datagram was.
enum class Accepted
{
  NONE,
  STATE,  ///< a state packet of the current session: packet(), twist estimates, lastGap()
  HELLO   ///< a hello: answer with a challenge carrying session() for consoleNonce()
};

/**
 * Authenticates and validates console datagrams, runs the session handshake and tracks the health
 * of the link (one per receiver). Session: a hello (tag valid) while no session is streaming
 * (no state packet in the current one for resync_after) opens a new session with a fresh nonce and
 * restarts the sequence; the caller answers every accepted hello with a challenge. A hello while a
 * session streams is refused (SESSION). State packets must carry the current session and a newer
 * sequence number. Rejections are counted per reason. Never throws on bad input, never allocates
 * in accept().
 */
class TouchballLink
{
public:
  /// @throws std::invalid_argument on a non-positive timeout, resync_after < timeout or a bad key
  TouchballLink(const LinkParams& p, const std::vector<std::uint8_t>& key, NonceSource nonce = randomNonce);

  /// Authenticate and validate one datagram of @p n bytes from IPv4 @p source_ip (host order)
  /// received at @p now [s]; on Reject::NONE, kind() says what it was.
  Reject accept(const std::uint8_t* data, std::size_t n, std::uint32_t source_ip, double now);

  Accepted kind() const { return kind_; }
  std::uint64_t session() const { return session_; }            ///< current session nonce (0: none)
  std::uint64_t consoleNonce() const { return console_nonce_; }  ///< nonce of the hello it answers
  std::uint64_t sessions() const { return sessions_; }           ///< sessions opened
  const Hmac& mac() const { return *mac_; }
  const StatePacket& packet() const { return packet_; }
  const TwistEstimator& twist(int device) const { return twist_[device]; }
  std::uint32_t lastGap() const { return gap_; }
  std::uint64_t received() const { return received_; }
  std::uint64_t gaps() const { return sequence_.gaps(); }
  std::uint64_t rejected(Reject r) const { return rejected_[static_cast<int>(r)]; }
  std::uint64_t rejectedTotal() const;
  /// "mac 3, size 2" (reasons with a non-zero count), "" if none.
  std::string rejectedSummary() const;
  Reject lastError() const { return last_error_; }
  bool hasValid() const { return has_valid_; }

  // ---- watchdog (deadline = last valid receive time + timeout)
  double timeout() const { return p_.timeout; }
  /// Seconds since the last valid packet (+inf if none yet).
  double inputAge(double now) const;
  bool isStale(double now) const { return inputAge(now) > p_.timeout; }
  /**
   * How long the receive thread may block waiting for a datagram [s]: up to the watchdog deadline
   * while streaming (0 if it has passed: look at what is queued, then declare), @p idle_wake while
   * already stale (heartbeat, shutdown).
   */
  double waitTime(double now, bool stale, double idle_wake) const;

private:
  Reject onHello(const std::uint8_t* data, double now);
  Reject onState(const std::uint8_t* data, double now);

  LinkParams p_;
  std::unique_ptr<Hmac> mac_;
  NonceSource nonce_;
  SequenceTracker sequence_;
  std::array<TwistEstimator, kDevices> twist_;
  StatePacket packet_, scratch_;
  std::array<std::uint64_t, kRejectReasons> rejected_{};
  std::uint64_t received_ = 0;
  std::uint32_t gap_ = 0;
  bool has_valid_ = false;
  double last_valid_ = 0.0;
  Reject last_error_ = Reject::NONE;
  Accepted kind_ = Accepted::NONE;
  std::uint64_t session_ = 0, console_nonce_ = 0, sessions_ = 0;
  std::uint64_t session_states_ = 0;  ///< state packets accepted in the current session
};

/**
 * Latest force command of one device, validated, clamped and aged. Older than @p max_age [s] or
 * never set => disabled zero command, so a dead teleoperation never leaves a force on the hand.
 */
class WrenchLatch
{
public:
  /// @throws std::invalid_argument unless max_force, max_torque >= 0 [N, N m] and max_age > 0 [s]
  WrenchLatch(double max_force = 3.3, double max_torque = 0.0, double max_age = 0.1);
  /// Store a command received at @p now; false (and zero command) if any value is not finite.
  bool set(const double force[3], const double torque[3], double now);
  /// Forget the command (zero force), e.g. a command in the wrong frame.
  void clear() { has_ = false; }
  DeviceCommand get(double now) const;

private:
  double max_force_, max_torque_, max_age_;
  DeviceCommand cmd_;
  bool has_ = false;
  double stamp_ = 0.0;
};

}  // namespace touchball
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_TOUCHBALL_LINK_H

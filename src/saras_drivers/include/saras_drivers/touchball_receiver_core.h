/**
 * @file touchball_receiver_core.h
 * @brief State the Touchball receiver shares between its receive thread and the ROS callback queue
 *        (ROS-agnostic): the link, the force command latches, the STALE/OK decision, and the health
 *        report (level, text, key/values) behind touchball/status and /diagnostics.
 *
 * Thread-safe: every member function takes the internal lock for a short, allocation-free copy
 * (except health(), called by the non-real-time status timer). Times "now" are a monotonic clock
 * [s]; units m, rad, s, N, N m, Hz.
 */
#ifndef SARAS_DRIVERS_TOUCHBALL_RECEIVER_CORE_H
#define SARAS_DRIVERS_TOUCHBALL_RECEIVER_CORE_H

#include <array>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "saras_drivers/touchball_link.h"
#include "saras_drivers/touchball_protocol.h"

namespace saras_drivers
{
namespace touchball
{
/// What the publishers need of one accepted packet, copied out of the link under the lock.
struct AcceptedPacket
{
  Accepted kind = Accepted::NONE;  ///< STATE: packet, twist, commands; HELLO: answer with a challenge
  std::uint64_t session = 0;       ///< session the answer (command or challenge) is bound to
  std::uint64_t console_nonce = 0; ///< HELLO: the console's nonce the challenge echoes
  StatePacket packet;
  double linear[kDevices][3] = {};   ///< [m/s] twist estimate per device (base frame)
  double angular[kDevices][3] = {};  ///< [rad/s]
  std::array<DeviceCommand, kDevices> commands;  ///< force commands to send back (aged, clamped)
};

/// Limits of the force commands (validated by WrenchLatch).
struct WrenchLimits
{
  double max_force = 3.3;         ///< [N] clamp of the force norm
  double max_torque = 0.0;        ///< [N m] clamp of the torque norm
  double wrench_timeout = 0.1;    ///< [s] older commands => zero force
};

/// Health level of the link (values as diagnostic_msgs/DiagnosticStatus and saras_msgs/ComponentStatus).
enum class LinkLevel : std::uint8_t
{
  OK = 0,
  STALE = 3
};

/// A consistent copy of the link's counters and state (see ReceiverCore::health).
struct LinkHealth
{
  LinkLevel level = LinkLevel::STALE;
  bool stalled = false;        ///< streaming, but no packet handled for stall_factor x timeout
  bool has_valid = false;      ///< a valid packet was ever received
  double input_age = 0.0;      ///< [s] since the last valid packet (+inf: none yet)
  double timeout = 0.0;        ///< [s] watchdog timeout
  std::uint64_t received = 0;  ///< accepted packets
  std::uint64_t gaps = 0;      ///< packets missing from the sequence
  std::array<std::uint64_t, kRejectReasons> rejected{};  ///< rejected datagrams per Reject reason
  std::uint64_t wrench_rejected = 0;  ///< force commands refused (wrong frame, non-finite)
  std::uint64_t send_errors = 0;      ///< command packets the socket refused to send
  std::uint64_t sessions = 0;         ///< sessions opened (hello answered with a new nonce)
  std::uint64_t rejectedDatagrams() const;
};

/**
 * Receive-thread / callback-queue hand-off of the receiver. The receive thread calls waitTime(),
 * accept() for each datagram and watchdog() when none came; the callback queue calls setWrench()
 * / rejectWrench() and, from its timers, latestPacket() and health().
 */
class ReceiverCore
{
public:
  /**
   * @param key the deployment key (readKeyFile), 32..64 bytes
   * @param nonce session nonce source (tests: deterministic)
   * @param stall_factor health() reports a stalled receive thread (STALE) when, while the thread
   *        still believes the link is streaming, no packet was handled for this many timeouts
   * @throws std::invalid_argument on invalid link parameters or wrench limits
   */
  ReceiverCore(const LinkParams& link, const WrenchLimits& wrench, const std::vector<std::uint8_t>& key,
               double stall_factor = 3.0, NonceSource nonce = randomNonce);

  // ---- receive thread
  /// How long the receive thread may wait for a datagram [s] (TouchballLink::waitTime).
  double waitTime(double now, double idle_wake) const;
  /**
   * Authenticate and validate a datagram from @p source_ip (host order) received at @p now, stamped
   * @p stamp_ns (the caller's clock for messages, [ns], handed to packetSince()). On Reject::NONE
   * @p out.kind says what it was: STATE => @p out holds the packet and the commands to answer
   * with, and @p resumed is true if the link was STALE until now (the caller reports OK);
   * HELLO => answer with encodeChallenge(out.session, out.console_nonce). Never allocates.
   */
  Reject accept(const std::uint8_t* data, std::size_t n, std::uint32_t source_ip, double now, std::int64_t stamp_ns,
                AcceptedPacket& out, bool& resumed);
  /// True exactly once when the watchdog deadline has passed while streaming (the link is STALE now).
  bool watchdog(double now);
  /// Count a command packet the socket could not send.
  void countSendError();
  bool stale() const;

  // ---- callback queue
  /// Latest command of @p device received at @p now; false (zero force, counted) if not finite.
  bool setWrench(int device, const double force[3], const double torque[3], double now);
  /// A command that cannot be used (e.g. wrong frame): zero force on @p device, counted.
  void rejectWrench(int device);
  /**
   * The last accepted packet and its receive stamp if it is newer than the one numbered @p seen
   * (accepted-packet count, 0 = none yet; updated); false if no packet came since.
   */
  bool packetSince(std::uint64_t& seen, StatePacket& out, std::int64_t& stamp_ns) const;
  /// Counters and state at @p now (the same values touchball/status and /diagnostics report).
  LinkHealth health(double now) const;
  const LinkParams& linkParams() const { return params_; }
  /// The link's HMAC (immutable after construction: usable from any thread).
  const Hmac& mac() const { return link_.mac(); }

private:
  LinkParams params_;
  double stall_factor_;
  mutable std::mutex mutex_;
  TouchballLink link_;
  std::array<WrenchLatch, kDevices> latches_;
  bool stale_ = true;
  std::int64_t stamp_ns_ = 0;
  std::uint64_t wrench_rejected_ = 0;
  std::uint64_t send_errors_ = 0;
};

/**
 * Packet rate from the accepted-packet counter, measured between successive calls (the
 * diagnostics period): no work on the receive path.
 */
class RateMeter
{
public:
  /// Rate [Hz] since the previous call (0 on the first call or if no time passed).
  double update(std::uint64_t count, double now);

private:
  bool has_prev_ = false;
  std::uint64_t count_ = 0;
  double t_ = 0.0;
};

/**
 * Rate limit of the rejection log lines, per reason: at most one line per @p period [s] per
 * reason, reporting how many of that reason were not logged since. Allocation-free (receive thread).
 */
class RejectLogLimiter
{
public:
  explicit RejectLogLimiter(double period = 1.0) : period_(period) {}
  /// True if a line for @p r may be written at @p now; @p suppressed = lines of r skipped since the last.
  bool allow(Reject r, double now, std::uint64_t& suppressed);

private:
  double period_;
  std::array<double, kRejectReasons> last_{};
  std::array<bool, kRejectReasons> has_{};
  std::array<std::uint64_t, kRejectReasons> skipped_{};
};

/// The health as reported on /diagnostics: level, one-line message and key/values.
struct HealthReport
{
  LinkLevel level = LinkLevel::STALE;
  std::string message;
  std::vector<std::pair<std::string, std::string>> values;
};

/**
 * One-line status text into @p out (allocation-free; also the message of touchball/status):
 * "streaming", "no valid packet from <source> for <age> ms (timeout <t> ms)", "no valid packet
 * from <source> yet" or "receive thread stalled: no packet handled for <age> ms".
 * @param source the accepted console, e.g. "127.0.0.1:5005" or "*:5005"
 */
const char* formatStatusText(const LinkHealth& h, const char* source, char* out, std::size_t size);

/**
 * The /diagnostics report of the link (keys documented in the package README):
 * "packet rate [Hz]", "packets received", "input age [ms]", "timeout [ms]", "sequence gaps",
 * "rejected datagrams", "rejected <reason>" for every Reject reason (foreign_source, size, magic,
 * version, type, mac, session, non_finite, quaternion, duplicate, out_of_order), "rejected wrench_cmd",
 * "command send errors", "sessions opened", "source".
 */
HealthReport describeHealth(const LinkHealth& h, double packet_rate, const char* source);

}  // namespace touchball
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_TOUCHBALL_RECEIVER_CORE_H

/**
 * @file touchball_udp.h
 * @brief The Touchball receiver's UDP socket (ROS-agnostic): bind, wait with a deadline, receive
 *        and send without blocking. Errors are returned as errno values, never thrown after the
 *        constructor, so the receive thread decides what to log. Allocation-free after construction.
 */
#ifndef SARAS_DRIVERS_TOUCHBALL_UDP_H
#define SARAS_DRIVERS_TOUCHBALL_UDP_H

#include <cstddef>
#include <cstdint>
#include <string>

namespace saras_drivers
{
namespace touchball
{
/// IPv4 address and port, host byte order.
struct Endpoint
{
  std::uint32_t ip = 0;
  std::uint16_t port = 0;
};

/// Parse a dotted IPv4 address ("127.0.0.1") into host byte order; false if it is not one.
bool parseIpv4(const std::string& text, std::uint32_t& ip);

/// "a.b.c.d:port" into @p out (at least 22 bytes); returns @p out. Allocation-free (logging).
const char* formatEndpoint(const Endpoint& e, char* out, std::size_t size);

/// Where the command packet answering a state packet from @p source goes: @p command_port of the
/// same host, or the source port itself if @p command_port is 0.
inline Endpoint commandDestination(const Endpoint& source, std::uint16_t command_port)
{
  Endpoint d = source;
  if (command_port != 0)
    d.port = command_port;
  return d;
}

/**
 * A bound, non-blocking UDP socket (IPv4). Not copyable; one thread receives, any thread may send.
 */
class UdpSocket
{
public:
  /**
   * Bind to @p bind_address : @p port (0: any free port, see localPort()).
   * @param receive_buffer [bytes] SO_RCVBUF requested (the kernel may grant less)
   * @throws std::runtime_error naming the address if the socket cannot be created or bound
   * @throws std::invalid_argument if @p bind_address is not an IPv4 address
   */
  UdpSocket(const std::string& bind_address, std::uint16_t port, int receive_buffer = 1 << 20);
  ~UdpSocket();
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  /// Port the socket is bound to (the one chosen by the kernel if 0 was asked).
  std::uint16_t localPort() const;

  /**
   * Wait at most @p timeout [s] (<= 0: do not wait) for a datagram.
   * @return 1 readable, 0 timed out or interrupted by a signal, -errno on a poll error
   */
  int wait(double timeout) const;

  /**
   * Take one datagram without blocking: its size (a datagram longer than @p capacity is truncated
   * to @p capacity, so give more room than any valid packet to keep oversize detectable) and its
   * @p source; -EAGAIN if none is queued, -errno on a socket error (e.g. an ICMP port unreachable
   * for an earlier send).
   */
  long receive(std::uint8_t* data, std::size_t capacity, Endpoint& source) const;

  /// Send @p n bytes to @p dest without blocking: 0, or the errno of the failure.
  int sendTo(const std::uint8_t* data, std::size_t n, const Endpoint& dest) const;

private:
  int fd_ = -1;
};

}  // namespace touchball
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_TOUCHBALL_UDP_H

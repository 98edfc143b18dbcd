/**
 * @file touchball_udp.cpp
 * @brief UDP socket of the Touchball receiver (POSIX).
 */
#include "saras_drivers/touchball_udp.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace saras_drivers
{
namespace touchball
{
namespace
{
sockaddr_in toSockaddr(const Endpoint& e)
{
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(e.ip);
  a.sin_port = htons(e.port);
  return a;
}
}  // namespace

bool parseIpv4(const std::string& text, std::uint32_t& ip)
{
  in_addr a{};
  if (inet_pton(AF_INET, text.c_str(), &a) != 1)
    return false;
  ip = ntohl(a.s_addr);
  return true;
}

const char* formatEndpoint(const Endpoint& e, char* out, std::size_t size)
{
  std::snprintf(out, size, "%u.%u.%u.%u:%u", (e.ip >> 24) & 0xffu, (e.ip >> 16) & 0xffu, (e.ip >> 8) & 0xffu,
                e.ip & 0xffu, static_cast<unsigned>(e.port));
  return out;
}

UdpSocket::UdpSocket(const std::string& bind_address, std::uint16_t port, int receive_buffer)
{
  Endpoint local;
  if (!parseIpv4(bind_address, local.ip))
    throw std::invalid_argument("'" + bind_address + "' is not an IPv4 address");
  local.port = port;
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd_ < 0)
    throw std::runtime_error(std::string("cannot create the UDP socket: ") + std::strerror(errno));
  ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
  const sockaddr_in a = toSockaddr(local);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0)
  {
    const std::string err = std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error("cannot listen on " + bind_address + ":" + std::to_string(port) + ": " + err);
  }
}

UdpSocket::~UdpSocket()
{
  if (fd_ >= 0)
    ::close(fd_);
}

std::uint16_t UdpSocket::localPort() const
{
  sockaddr_in a{};
  socklen_t len = sizeof a;
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0)
    return 0;
  return ntohs(a.sin_port);
}

int UdpSocket::wait(double timeout) const
{
  pollfd pfd{ fd_, POLLIN, 0 };
  timespec ts{};
  if (timeout > 0.0)
  {
    ts.tv_sec = static_cast<time_t>(timeout);
    ts.tv_nsec = static_cast<long>((timeout - static_cast<double>(ts.tv_sec)) * 1e9);
  }
  const int r = ::ppoll(&pfd, 1, &ts, nullptr);
  if (r > 0)
    return 1;
  if (r == 0 || errno == EINTR)
    return 0;
  return -errno;
}

long UdpSocket::receive(std::uint8_t* data, std::size_t capacity, Endpoint& source) const
{
  sockaddr_in src{};
  socklen_t len = sizeof src;
  const ssize_t n = ::recvfrom(fd_, data, capacity, MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&src), &len);
  if (n < 0)
    return errno == EWOULDBLOCK || errno == EINTR ? -EAGAIN : -errno;
  source.ip = ntohl(src.sin_addr.s_addr);
  source.port = ntohs(src.sin_port);
  return static_cast<long>(n);
}

int UdpSocket::sendTo(const std::uint8_t* data, std::size_t n, const Endpoint& dest) const
{
  const sockaddr_in a = toSockaddr(dest);
  if (::sendto(fd_, data, n, MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&a), sizeof a) < 0)
    return errno;
  return 0;
}

}  // namespace touchball
}  // namespace saras_drivers

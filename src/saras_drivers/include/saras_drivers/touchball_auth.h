/**
 * @file touchball_auth.h
 * @brief Authentication pieces of the Touchball protocol v2 (docs/touchball_protocol.md): the
 *        per-deployment key file, HMAC-SHA256 tags and random session nonces.
 *
 * ROS-agnostic. Tagging is allocation-free: the HMAC inner and outer pad states are hashed once
 * when the key is set, and every tag copies them (OpenSSL libcrypto's SHA-256 block functions; the
 * EVP interface of OpenSSL 3.0 allocates twice per MAC, which the receive thread must not do). The
 * gtest checks the tags against EVP's HMAC and the documented test vectors.
 */
#ifndef SARAS_DRIVERS_TOUCHBALL_AUTH_H
#define SARAS_DRIVERS_TOUCHBALL_AUTH_H

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace saras_drivers
{
namespace touchball
{
constexpr std::size_t kTagSize = 16;     ///< [bytes] HMAC-SHA256 truncated to its first 128 bits
constexpr std::size_t kMinKeySize = 32;  ///< [bytes] shortest key accepted (256 bits)
constexpr std::size_t kMaxKeySize = 64;  ///< [bytes] one SHA-256 block: longer keys are refused

/**
 * Read a key file: one line of 2 x N hexadecimal digits (N = 32..64 bytes), optional comment lines
 * starting with '#', nothing else. The file must exist, be a regular file and not be readable or
 * writable by group or others (mode 0600 or 0400).
 * @throws std::runtime_error naming @p path and the problem
 */
std::vector<std::uint8_t> readKeyFile(const std::string& path);

/// Parse the key text (the content of a key file); @throws std::runtime_error on a malformed key.
std::vector<std::uint8_t> parseKeyText(const std::string& text);

/// A random, non-zero 64-bit nonce from the kernel's CSPRNG (getrandom(2)); @throws std::runtime_error
std::uint64_t randomNonce();

/**
 * HMAC-SHA256 (RFC 2104) with a fixed key, truncated to kTagSize bytes. tag() and verify() are
 * allocation-free and may be called from one thread at a time per object.
 */
class Hmac
{
public:
  /// @throws std::invalid_argument unless kMinKeySize <= key size <= kMaxKeySize
  explicit Hmac(const std::vector<std::uint8_t>& key);
  ~Hmac();
  Hmac(const Hmac&) = delete;
  Hmac& operator=(const Hmac&) = delete;

  /// Full 32-byte HMAC-SHA256 of @p n bytes.
  void full(const std::uint8_t* data, std::size_t n, std::uint8_t out[32]) const;
  /// First kTagSize bytes of the HMAC of @p n bytes into @p out.
  void tag(const std::uint8_t* data, std::size_t n, std::uint8_t* out) const;
  /// True if @p expected (kTagSize bytes) is the tag of @p n bytes (constant-time comparison).
  bool verify(const std::uint8_t* data, std::size_t n, const std::uint8_t* expected) const;

private:
  struct State;
  State* inner_;  ///< SHA-256 state after the key ^ ipad block
  State* outer_;  ///< after the key ^ opad block
};

}  // namespace touchball
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_TOUCHBALL_AUTH_H

/**
 * @file packet_builder.h
 * @brief Test-side encoder of Touchball v2 packets, independent of the code under test
 *        (little-endian host assumed, as on every ROS target; tag from OpenSSL's one-shot HMAC()).
 */
#ifndef SARAS_DRIVERS_TEST_TOUCHBALL_PACKET_BUILDER_H
#define SARAS_DRIVERS_TEST_TOUCHBALL_PACKET_BUILDER_H

#include <openssl/evp.h>
#include <openssl/hmac.h>

#include <cstdint>
#include <cstring>
#include <vector>

namespace touchball_test
{
/// The test key: bytes 0x00..0x1f (as in the document's test vectors).
inline std::vector<std::uint8_t> testKey()
{
  std::vector<std::uint8_t> k(32);
  for (std::size_t i = 0; i < k.size(); ++i)
    k[i] = static_cast<std::uint8_t>(i);
  return k;
}

constexpr std::uint64_t kSession = 0x0123456789ABCDEFull;  ///< session nonce the test links issue
constexpr std::uint64_t kConsoleNonce = 0x1122334455667788ull;

/// Full HMAC-SHA256 of @p n bytes under @p key (OpenSSL's EVP-based one-shot HMAC()).
inline std::vector<std::uint8_t> hmacSha256(const std::vector<std::uint8_t>& key, const std::uint8_t* d,
                                            std::size_t n)
{
  std::vector<std::uint8_t> out(32);
  unsigned int len = 0;
  HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), d, n, out.data(), &len);
  return out;
}

/// Append the 16-byte tag of everything in @p b.
inline std::vector<std::uint8_t> sign(std::vector<std::uint8_t> b, const std::vector<std::uint8_t>& key = testKey())
{
  const std::vector<std::uint8_t> h = hmacSha256(key, b.data(), b.size());
  b.insert(b.end(), h.begin(), h.begin() + 16);
  return b;
}

/// A hello (44 bytes) with the console's nonce.
inline std::vector<std::uint8_t> hello(std::uint64_t nonce = kConsoleNonce, const std::vector<std::uint8_t>& key = testKey())
{
  std::vector<std::uint8_t> b(28, 0);
  std::memcpy(b.data(), "TBAL", 4);
  b[4] = 2;
  b[5] = 3;
  std::memcpy(&b[20], &nonce, 8);
  return sign(b, key);
}

/// A valid state packet (both devices at rest, identity orientation) to modify field by field.
struct Builder
{
  std::vector<std::uint8_t> b = std::vector<std::uint8_t>(164, 0);
  Builder(std::uint32_t seq, double t, std::uint64_t session = kSession)
  {
    std::memcpy(b.data(), "TBAL", 4);
    b[4] = 2;
    b[5] = 1;
    std::memcpy(&b[8], &seq, 4);
    std::memcpy(&b[12], &t, 8);
    std::memcpy(&b[20], &session, 8);
    for (int d = 0; d < 2; ++d)
    {
      const double pos[3] = { -0.1, 0.02 * d, 0.08 }, q[4] = { 0, 0, 0, 1 };
      std::memcpy(&b[28 + 68 * d], pos, 24);
      std::memcpy(&b[52 + 68 * d], q, 32);
    }
  }
  Builder& f64(std::size_t off, double v)
  {
    std::memcpy(&b[off], &v, 8);
    return *this;
  }
  std::vector<std::uint8_t> done(const std::vector<std::uint8_t>& key = testKey()) const { return sign(b, key); }
};

}  // namespace touchball_test

#endif  // SARAS_DRIVERS_TEST_TOUCHBALL_PACKET_BUILDER_H

/**
 * @file test_touchball_auth.cpp
 * @brief Touchball v2 authentication: the documented test vectors (test/touchball/data/
 *        test_vectors.txt, also checked by the Python tests), tags against OpenSSL's HMAC(), key file
 *        rules, no OpenSSL allocation per tag, and the cost of a tag.
 */
#include <gtest/gtest.h>
#include <openssl/crypto.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "saras_drivers/touchball_protocol.h"
#include "packet_builder.h"

using namespace saras_drivers::touchball;

namespace
{
std::atomic<long> g_openssl_allocations{ 0 };

void* countMalloc(std::size_t n, const char*, int)
{
  ++g_openssl_allocations;
  return std::malloc(n);
}
void* countRealloc(void* p, std::size_t n, const char*, int)
{
  ++g_openssl_allocations;
  return std::realloc(p, n);
}
void plainFree(void* p, const char*, int)
{
  std::free(p);
}

std::vector<std::uint8_t> unhex(const std::string& h)
{
  std::vector<std::uint8_t> out(h.size() / 2);
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = static_cast<std::uint8_t>(std::stoul(h.substr(2 * i, 2), nullptr, 16));
  return out;
}

struct Vector
{
  std::string name;
  std::vector<std::uint8_t> key, packet, hmac;
};

std::vector<Vector> vectors()
{
  std::ifstream f(TOUCHBALL_TEST_DATA "/test_vectors.txt");
  std::vector<Vector> out;
  std::string line;
  while (std::getline(f, line))
  {
    if (line.empty() || line[0] == '#')
      continue;
    std::istringstream in(line);
    std::string name, key, packet, mac;
    in >> name >> key >> packet >> mac;
    out.push_back({ name, unhex(key), unhex(packet), unhex(mac) });
  }
  return out;
}

std::string tempKeyFile(const std::string& text, mode_t mode)
{
  char path[] = "/tmp/touchball_key_XXXXXX";
  const int fd = mkstemp(path);
  EXPECT_GE(fd, 0);
  EXPECT_EQ(write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  close(fd);
  chmod(path, mode);
  return path;
}
}  // namespace

/// Called from main before anything else uses OpenSSL: counts its allocations.
void installOpenSslAllocationCounter()
{
  CRYPTO_set_mem_functions(countMalloc, countRealloc, plainFree);
}

TEST(TouchballAuth, TestVectors)
{
  const std::vector<Vector> vs = vectors();
  ASSERT_EQ(vs.size(), 4u);
  for (const Vector& v : vs)
  {
    const Hmac mac(v.key);
    const std::size_t n = v.packet.size() - kTagSize;
    std::uint8_t full[32];
    mac.full(v.packet.data(), n, full);
    EXPECT_EQ(std::vector<std::uint8_t>(full, full + 32), v.hmac) << v.name;
    EXPECT_EQ(touchball_test::hmacSha256(v.key, v.packet.data(), n), v.hmac) << v.name;
    EXPECT_TRUE(mac.verify(v.packet.data(), n, v.packet.data() + n)) << v.name;
  }
  // the state vector decodes; the command and challenge vectors are what the encoders produce
  const Hmac mac(vs[0].key);
  std::uint8_t type = 0;
  ASSERT_EQ(checkFrame(vs[0].packet.data(), vs[0].packet.size(), mac, type), Reject::NONE);
  StatePacket p;
  ASSERT_EQ(decodeState(vs[0].packet.data(), touchball_test::kSession, p), Reject::NONE);
  EXPECT_EQ(p.seq, 0xFFFFFFFEu);
  EXPECT_DOUBLE_EQ(p.sender_time, 1700000000.25);
  EXPECT_DOUBLE_EQ(p.devices[0].position[0], -0.12);
  EXPECT_TRUE(p.devices[0].clutch());
  EXPECT_TRUE(p.devices[1].clipButton());
  std::array<DeviceCommand, 2> c;
  c[0].force[0] = 1.0;
  c[0].force[1] = -2.0;
  c[0].force[2] = 0.5;
  c[0].enabled = true;
  std::vector<std::uint8_t> out(kCommandSize);
  encodeCommand(7, 12.5, touchball_test::kSession, c, mac, out.data());
  EXPECT_EQ(out, vs[1].packet);
  ASSERT_EQ(checkFrame(vs[2].packet.data(), vs[2].packet.size(), mac, type), Reject::NONE);
  EXPECT_EQ(type, kTypeHello);
  Hello h;
  ASSERT_EQ(decodeHello(vs[2].packet.data(), h), Reject::NONE);
  EXPECT_EQ(h.console_nonce, touchball_test::kConsoleNonce);
  out.resize(kChallengeSize);
  encodeChallenge(1, 1700000000.125, touchball_test::kSession, touchball_test::kConsoleNonce, mac, out.data());
  EXPECT_EQ(out, vs[3].packet);
}

TEST(TouchballAuth, TagIsAllocationFreeAndCheap)
{
  const Hmac mac(touchball_test::testKey());
  const std::vector<std::uint8_t> d = touchball_test::Builder(1, 2.0).done();
  const long before = g_openssl_allocations;
  const auto t0 = std::chrono::steady_clock::now();
  constexpr int kN = 20000;
  int ok = 0;
  for (int i = 0; i < kN; ++i)
    ok += mac.verify(d.data(), kStateSize - kTagSize, d.data() + kStateSize - kTagSize);
  const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / kN;
  EXPECT_EQ(ok, kN);
  EXPECT_EQ(g_openssl_allocations - before, 0) << "OpenSSL allocated on the tag path";
  std::printf("[ cost     ] HMAC-SHA256 verify of a 180-byte state packet: %.2f us (mean of %d)\n", us, kN);
}

TEST(TouchballAuth, KeyFileRules)
{
  const std::string hex(64, 'a');
  const std::string good = tempKeyFile("# console link\n" + hex + "\n", 0600);
  EXPECT_EQ(readKeyFile(good), std::vector<std::uint8_t>(32, 0xaa));
  chmod(good.c_str(), 0640);
  try
  {
    readKeyFile(good);
    ADD_FAILURE() << "a group-readable key file was accepted";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(good), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0640"), std::string::npos) << e.what();
  }
  chmod(good.c_str(), 0604);
  EXPECT_THROW(readKeyFile(good), std::runtime_error);
  std::remove(good.c_str());
  try
  {
    readKeyFile(good);
    ADD_FAILURE() << "a missing key file was accepted";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(good), std::string::npos) << e.what();
  }
  EXPECT_THROW(readKeyFile(""), std::runtime_error);
  EXPECT_THROW(parseKeyText(std::string(62, 'a')), std::runtime_error);   // 31 bytes
  EXPECT_THROW(parseKeyText(std::string(130, 'a')), std::runtime_error);  // 65 bytes
  EXPECT_THROW(parseKeyText(std::string(63, 'a') + "g"), std::runtime_error);
  EXPECT_THROW(parseKeyText(hex + "\n" + hex), std::runtime_error);
  EXPECT_EQ(parseKeyText("  " + hex + "  \r\n").size(), 32u);
  EXPECT_THROW(Hmac(std::vector<std::uint8_t>(16, 1)), std::invalid_argument);
  EXPECT_NE(randomNonce(), 0u);
  EXPECT_NE(randomNonce(), randomNonce());
}

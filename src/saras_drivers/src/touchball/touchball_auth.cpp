/**
 * @file touchball_auth.cpp
 * @brief Key file, HMAC-SHA256 tags and nonces of the Touchball protocol v2.
 */
// SHA256_Init/Update/Final are deprecated in OpenSSL 3.0 in favour of EVP, whose digest contexts
// allocate on every re-initialisation; the block functions work on a caller-owned state.
#define OPENSSL_SUPPRESS_DEPRECATED
#include "saras_drivers/touchball_auth.h"

#include <sys/random.h>
#include <sys/stat.h>

#include <openssl/crypto.h>
#include <openssl/sha.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace saras_drivers
{
namespace touchball
{
struct Hmac::State
{
  SHA256_CTX ctx;
};

namespace
{
int hexDigit(char c)
{
  if (c >= '0' && c <= '9')
    return c - '0';
  c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
}
}  // namespace

std::vector<std::uint8_t> parseKeyText(const std::string& text)
{
  std::istringstream in(text);
  std::string line, hex;
  while (std::getline(in, line))
  {
    const std::size_t a = line.find_first_not_of(" \t\r");
    if (a == std::string::npos || line[a] == '#')
      continue;
    const std::size_t b = line.find_last_not_of(" \t\r");
    if (!hex.empty())
      throw std::runtime_error("more than one key line");
    hex = line.substr(a, b - a + 1);
  }
  if (hex.size() % 2 != 0 || hex.size() < 2 * kMinKeySize || hex.size() > 2 * kMaxKeySize)
    throw std::runtime_error("the key must be one line of 64 to 128 hexadecimal digits (32 to 64 bytes)");
  std::vector<std::uint8_t> key(hex.size() / 2);
  for (std::size_t i = 0; i < key.size(); ++i)
  {
    const int hi = hexDigit(hex[2 * i]), lo = hexDigit(hex[2 * i + 1]);
    if (hi < 0 || lo < 0)
      throw std::runtime_error("the key holds a character that is not a hexadecimal digit");
    key[i] = static_cast<std::uint8_t>(hi << 4 | lo);
  }
  return key;
}

std::vector<std::uint8_t> readKeyFile(const std::string& path)
{
  if (path.empty())
    throw std::runtime_error("no key file given (~key_file is empty)");
  struct stat st;
  if (::stat(path.c_str(), &st) != 0)
    throw std::runtime_error("key file " + path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode))
    throw std::runtime_error("key file " + path + " is not a regular file");
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0)
  {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw std::runtime_error("key file " + path + " has mode " + mode +
                             ": group/others may access it; run chmod 600 " + path);
  }
  std::ifstream f(path);
  if (!f)
    throw std::runtime_error("key file " + path + ": cannot open");
  std::stringstream text;
  text << f.rdbuf();
  try
  {
    return parseKeyText(text.str());
  }
  catch (const std::runtime_error& e)
  {
    throw std::runtime_error("key file " + path + ": " + e.what());
  }
}

std::uint64_t randomNonce()
{
  std::uint64_t v = 0;
  while (v == 0)
  {
    if (::getrandom(&v, sizeof v, 0) != static_cast<ssize_t>(sizeof v))
      throw std::runtime_error(std::string("getrandom: ") + std::strerror(errno));
  }
  return v;
}

Hmac::Hmac(const std::vector<std::uint8_t>& key) : inner_(new State), outer_(new State)
{
  if (key.size() < kMinKeySize || key.size() > kMaxKeySize)
  {
    delete inner_;
    delete outer_;
    throw std::invalid_argument("HMAC key must be 32 to 64 bytes");
  }
  std::uint8_t ipad[SHA256_CBLOCK], opad[SHA256_CBLOCK];
  for (std::size_t i = 0; i < SHA256_CBLOCK; ++i)
  {
    const std::uint8_t k = i < key.size() ? key[i] : 0;
    ipad[i] = k ^ 0x36;
    opad[i] = k ^ 0x5c;
  }
  SHA256_Init(&inner_->ctx);
  SHA256_Update(&inner_->ctx, ipad, sizeof ipad);
  SHA256_Init(&outer_->ctx);
  SHA256_Update(&outer_->ctx, opad, sizeof opad);
  OPENSSL_cleanse(ipad, sizeof ipad);
  OPENSSL_cleanse(opad, sizeof opad);
}

Hmac::~Hmac()
{
  OPENSSL_cleanse(inner_, sizeof *inner_);
  OPENSSL_cleanse(outer_, sizeof *outer_);
  delete inner_;
  delete outer_;
}

void Hmac::full(const std::uint8_t* data, std::size_t n, std::uint8_t out[32]) const
{
  SHA256_CTX c = inner_->ctx;
  std::uint8_t h[SHA256_DIGEST_LENGTH];
  SHA256_Update(&c, data, n);
  SHA256_Final(h, &c);
  c = outer_->ctx;
  SHA256_Update(&c, h, sizeof h);
  SHA256_Final(out, &c);
  OPENSSL_cleanse(&c, sizeof c);
}

void Hmac::tag(const std::uint8_t* data, std::size_t n, std::uint8_t* out) const
{
  std::uint8_t h[SHA256_DIGEST_LENGTH];
  full(data, n, h);
  std::memcpy(out, h, kTagSize);
}

bool Hmac::verify(const std::uint8_t* data, std::size_t n, const std::uint8_t* expected) const
{
  std::uint8_t t[kTagSize];
  tag(data, n, t);
  return CRYPTO_memcmp(t, expected, kTagSize) == 0;
}

}  // namespace touchball
}  // namespace saras_drivers

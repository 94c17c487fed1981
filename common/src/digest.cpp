#include "skillbus/digest.hpp"

// The low-level SHA-256 (as auth.cpp's MAC): OpenSSL 3's EVP digests fetch the algorithm
// at every init, and a lockstep participant finishes a digest or two every frame (the
// fetch was most of a skill manager's ack).
#define OPENSSL_SUPPRESS_DEPRECATED
#include <openssl/sha.h>

#include <stdexcept>

namespace skillbus {

Sha256::Sha256() : ctx_(new SHA256_CTX) {
  if (SHA256_Init(static_cast<SHA256_CTX*>(ctx_)) != 1) {
    delete static_cast<SHA256_CTX*>(ctx_);
    throw std::runtime_error("OpenSSL SHA-256 unavailable");
  }
}

Sha256::~Sha256() { delete static_cast<SHA256_CTX*>(ctx_); }

void Sha256::update(const void* data, size_t size) { SHA256_Update(static_cast<SHA256_CTX*>(ctx_), data, size); }

void Sha256::update_str(const std::string& s) { update_bytes(reinterpret_cast<const uint8_t*>(s.data()), s.size()); }

void Sha256::update_bytes(const uint8_t* data, size_t size) {
  const uint32_t n = static_cast<uint32_t>(size);
  const uint8_t len[4] = {uint8_t(n), uint8_t(n >> 8), uint8_t(n >> 16), uint8_t(n >> 24)};
  update(len, 4);
  update(data, size);
}

void Sha256::update_i64(int64_t v) {
  uint8_t b[8];
  for (int i = 0; i < 8; ++i) b[i] = uint8_t(uint64_t(v) >> (8 * i));
  update(b, 8);
}

Digest Sha256::finish() {
  Digest d{};
  auto* ctx = static_cast<SHA256_CTX*>(ctx_);
  SHA256_Final(d.data(), ctx);
  SHA256_Init(ctx);
  return d;
}

std::string to_hex(const Digest& d) {
  static const char* h = "0123456789abcdef";
  std::string s;
  for (uint8_t b : d) { s += h[b >> 4]; s += h[b & 15]; }
  return s;
}

}  // namespace skillbus

// SHA-256 (OpenSSL) as a running digest of what is published under lockstep. The same
// byte stream gives the same digest in C++ and Python (hashlib.sha256).
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace skillbus {

using Digest = std::array<uint8_t, 32>;

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void update(const void* data, size_t size);
  void update_str(const std::string& s);  // length-prefixed (u32 little endian), then bytes
  void update_bytes(const uint8_t* data, size_t size);  // as update_str
  void update_i64(int64_t v);             // 8 bytes little endian
  Digest finish();                        // and resets for the next use

 private:
  void* ctx_;
};

std::string to_hex(const Digest& d);

}  // namespace skillbus

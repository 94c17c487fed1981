// float32 as little-endian bytes whatever the host's order: the byte layout of the depth
// cameras' points (lcmtypes/camera_cloud_t.lcm), written by the physics server and read
// by the map server and the tests.
#pragma once

#include <cstdint>
#include <cstring>

namespace skillbus {

inline void put_f32_le(float f, uint8_t* out) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  for (int i = 0; i < 4; ++i) out[i] = static_cast<uint8_t>(u >> (8 * i));
}

inline float get_f32_le(const uint8_t* in) {
  uint32_t u = 0;
  for (int i = 0; i < 4; ++i) u |= static_cast<uint32_t>(in[i]) << (8 * i);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

}  // namespace skillbus

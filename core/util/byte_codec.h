// Little-endian byte writing and bounds-checked reading for the stored
// binary records (lmd_codec.h, place_features.h). A Reader never reads past
// its input: every getter returns false once the bytes run out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

namespace lmd {

inline void PutU16(std::string& out, uint16_t v) {
  out.push_back(static_cast<char>(v & 0xff));
  out.push_back(static_cast<char>(v >> 8));
}

inline void PutU32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

inline void PutU64(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

inline void PutF32(std::string& out, float f) {
  uint32_t v;
  std::memcpy(&v, &f, 4);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

inline void PutF64(std::string& out, double d) {
  uint64_t v;
  std::memcpy(&v, &d, 8);
  PutU64(out, v);
}

inline void PutVarint(std::string& out, uint64_t n) {
  for (;; n >>= 7) {
    if (n < 0x80) {
      out.push_back(static_cast<char>(n));
      return;
    }
    out.push_back(static_cast<char>((n & 0x7f) | 0x80));
  }
}

class ByteReader {
 public:
  explicit ByteReader(const std::string& s) : p_(reinterpret_cast<const uint8_t*>(s.data())), left_(s.size()) {}
  size_t left() const { return left_; }
  bool U8(uint8_t* v) {
    if (left_ < 1) return false;
    *v = *p_++, --left_;
    return true;
  }
  bool U16(uint16_t* v) {
    if (left_ < 2) return false;
    *v = static_cast<uint16_t>(p_[0] | (p_[1] << 8));
    p_ += 2, left_ -= 2;
    return true;
  }
  bool U64(uint64_t* v) {
    if (left_ < 8) return false;
    *v = 0;
    for (int i = 7; i >= 0; --i) *v = (*v << 8) | p_[i];
    p_ += 8, left_ -= 8;
    return true;
  }
  bool F32(float* f) {
    if (left_ < 4) return false;
    const uint32_t v = static_cast<uint32_t>(p_[0]) | (static_cast<uint32_t>(p_[1]) << 8) |
                       (static_cast<uint32_t>(p_[2]) << 16) | (static_cast<uint32_t>(p_[3]) << 24);
    std::memcpy(f, &v, 4);
    p_ += 4, left_ -= 4;
    return true;
  }
  bool Varint(uint64_t* v) {
    *v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      uint8_t b;
      if (!U8(&b)) return false;
      *v |= static_cast<uint64_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) return true;
    }
    return false;
  }

 private:
  const uint8_t* p_;
  size_t left_;
};

}  // namespace lmd

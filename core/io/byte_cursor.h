// Bounds-checked reading of binary records (MCAP, ROS 1 bags, CDR): a cursor
// over a byte span that never reads past its end and knows where its bytes
// sit in the file, so that errors can name an offset. Little-endian unless
// set_big_endian (CDR's big-endian encapsulation).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>

namespace lmd {

class ByteCursor {
 public:
  // `bytes` must outlive the cursor; `file_offset` is where bytes[0] sits.
  explicit ByteCursor(std::string_view bytes, uint64_t file_offset = 0)
      : data_(reinterpret_cast<const uint8_t*>(bytes.data())), size_(bytes.size()), base_(file_offset) {}

  size_t pos() const { return pos_; }
  size_t left() const { return size_ - pos_; }
  bool done() const { return pos_ == size_; }
  // File offset of the next byte.
  uint64_t offset() const { return base_ + pos_; }
  void set_big_endian(bool big) { big_endian_ = big; }

  bool Skip(size_t n) {
    if (n > left()) return false;
    pos_ += n;
    return true;
  }
  // Skips to the next multiple of n (a power of two) from the cursor's start.
  bool Align(size_t n) {
    const size_t pad = (n - (pos_ & (n - 1))) & (n - 1);
    return Skip(pad);
  }
  bool U8(uint8_t* v) { return Fixed(v); }
  bool U16(uint16_t* v) { return Fixed(v); }
  bool U32(uint32_t* v) { return Fixed(v); }
  bool U64(uint64_t* v) { return Fixed(v); }
  bool I32(int32_t* v) { return Fixed(v); }
  bool F32(float* v) { return Fixed(v); }
  bool F64(double* v) { return Fixed(v); }
  // The next n bytes as a view into the input.
  bool Bytes(size_t n, std::string_view* v) {
    if (n > left()) return false;
    *v = std::string_view(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return true;
  }
  // A u32-length-prefixed byte string (MCAP strings and byte arrays).
  bool PrefixedU32(std::string_view* v) {
    uint32_t n = 0;
    const size_t at = pos_;
    if (!U32(&n) || !Bytes(n, v)) return pos_ = at, false;
    return true;
  }
  bool PrefixedU64(std::string_view* v) {
    uint64_t n = 0;
    const size_t at = pos_;
    if (!U64(&n) || n > left() || !Bytes(static_cast<size_t>(n), v)) return pos_ = at, false;
    return true;
  }
  std::string_view Rest() const {
    return std::string_view(reinterpret_cast<const char*>(data_ + pos_), size_ - pos_);
  }

 private:
  template <typename T>
  bool Fixed(T* v) {
    if (sizeof(T) > left()) return false;
    uint8_t b[sizeof(T)];
    std::memcpy(b, data_ + pos_, sizeof(T));
    if (big_endian_) {
      for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    }
    std::memcpy(v, b, sizeof(T));  // the build targets little-endian hosts (x86-64, arm64)
    pos_ += sizeof(T);
    return true;
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  uint64_t base_;
  bool big_endian_ = false;
};

}  // namespace lmd

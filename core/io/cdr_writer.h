// Serialisation of ROS 2 messages in little-endian CDR (XCDR1, the
// encapsulation rosbag2 records and `ros2 bag play` publishes): a 4-byte
// header, then primitives aligned to their size from the end of the header.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "core/util/byte_codec.h"

namespace lmd {

class CdrWriter {
 public:
  CdrWriter() { out_.assign("\x00\x01\x00\x00", 4); }  // CDR_LE

  void U8(uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void U32(uint32_t v) { Align(4), PutU32(out_, v); }
  void I32(int32_t v) { U32(static_cast<uint32_t>(v)); }
  void F32(float v) { Align(4), PutF32(out_, v); }
  void F64(double v) { Align(8), PutF64(out_, v); }
  // A string: length with its NUL, the bytes, the NUL.
  void String(std::string_view s) {
    U32(static_cast<uint32_t>(s.size() + 1));
    out_.append(s.data(), s.size());
    out_.push_back('\0');
  }
  // builtin_interfaces/Time from nanoseconds.
  void Stamp(int64_t ns) {
    I32(static_cast<int32_t>(ns / 1000000000));
    U32(static_cast<uint32_t>(ns % 1000000000));
  }
  // std_msgs/Header.
  void Header(int64_t stamp_ns, std::string_view frame_id) { Stamp(stamp_ns), String(frame_id); }
  void Raw(std::string_view bytes) { out_.append(bytes.data(), bytes.size()); }
  void Align(size_t n) {
    while ((out_.size() - 4) % n != 0) out_.push_back('\0');
  }
  const std::string& data() const { return out_; }

 private:
  std::string out_;
};

}  // namespace lmd

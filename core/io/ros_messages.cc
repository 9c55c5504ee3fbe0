#include "core/io/ros_messages.h"

#include <type_traits>

#include "core/io/byte_cursor.h"

namespace lmd {
namespace {

// Reads ROS 2 CDR (aligned, after a 4-byte encapsulation header) or ROS 1
// (packed little-endian) primitives; remembers the first failure.
class Decoder {
 public:
  Decoder(std::string_view data, MessageEncoding encoding, const char* type)
      : in_(data), cdr_(encoding == MessageEncoding::kCdr), type_(type) {
    if (encoding != MessageEncoding::kCdr && encoding != MessageEncoding::kRos1) {
      Fail("the topic's encoding is neither cdr nor ros1");
      return;
    }
    if (cdr_) {
      std::string_view header;
      if (!in_.Bytes(4, &header)) {
        Fail("shorter than the 4-byte CDR encapsulation header");
        return;
      }
      const uint8_t kind = static_cast<uint8_t>(header[1]);
      if (header[0] != 0 || kind > 1) {
        Fail("unsupported CDR encapsulation " + std::to_string(static_cast<uint8_t>(header[0])) + "." +
             std::to_string(kind) + " (plain CDR, 0.0 or 0.1, is read)");
        return;
      }
      in_ = ByteCursor(data.substr(4));
      in_.set_big_endian(kind == 0);
      offset_ = 4;
    }
  }

  bool ok() const { return error_.empty(); }
  Status status() const {
    return Status::InvalidArgument(std::string(type_) + (cdr_ ? " (CDR): " : " (ROS 1): ") + error_);
  }

  void U32(uint32_t* v, const char* what) { Prim(v, 4, what); }
  void I32(int32_t* v, const char* what) { Prim(v, 4, what); }
  void F32(float* v, const char* what) { Prim(v, 4, what); }
  void F64(double* v, const char* what) { Prim(v, 8, what); }

  void String(std::string* s, const char* what) {
    uint32_t n = 0;
    U32(&n, what);
    if (!ok()) return;
    std::string_view bytes;
    if (!in_.Bytes(n, &bytes)) return Fail(std::string(what) + ": string of " + std::to_string(n) +
                                           " bytes declared, " + std::to_string(in_.left()) + " left");
    if (cdr_ && !bytes.empty() && bytes.back() == '\0') bytes.remove_suffix(1);
    s->assign(bytes.data(), bytes.size());
  }

  void Stamp(int64_t* ns, const char* what) {
    uint32_t sec = 0, nsec = 0;
    if (cdr_) {
      int32_t s = 0;
      I32(&s, what);
      U32(&nsec, what);
      *ns = static_cast<int64_t>(s) * 1000000000 + nsec;
    } else {
      U32(&sec, what);
      U32(&nsec, what);
      *ns = static_cast<int64_t>(sec) * 1000000000 + nsec;
    }
  }

  // std_msgs/Header (ROS 1 has a seq first).
  void Header(int64_t* stamp, std::string* frame) {
    if (!cdr_) {
      uint32_t seq = 0;
      U32(&seq, "header.seq");
    }
    Stamp(stamp, "header.stamp");
    String(frame, "header.frame_id");
  }

  void Float32Array(std::vector<float>* v, const char* what) {
    uint32_t n = 0;
    U32(&n, what);
    if (!ok()) return;
    if (static_cast<uint64_t>(n) * 4 > in_.left()) {
      return Fail(std::string(what) + ": " + std::to_string(n) + " values declared, " + std::to_string(in_.left()) +
                  " bytes left");
    }
    v->resize(n);
    for (uint32_t i = 0; i < n && ok(); ++i) F32(&(*v)[i], what);
  }

  // The count of a sequence whose elements take at least min_bytes each.
  uint32_t Count(size_t min_bytes, const char* what) {
    uint32_t n = 0;
    U32(&n, what);
    if (ok() && static_cast<uint64_t>(n) * min_bytes > in_.left()) {
      Fail(std::string(what) + ": " + std::to_string(n) + " elements declared, " + std::to_string(in_.left()) +
           " bytes left");
      return 0;
    }
    return n;
  }

  void Transform(Transform3* t, const char* what) {
    F64(&t->x, what), F64(&t->y, what), F64(&t->z, what);
    F64(&t->qx, what), F64(&t->qy, what), F64(&t->qz, what), F64(&t->qw, what);
  }

  void SkipF64(size_t n, const char* what) {
    for (size_t i = 0; i < n && ok(); ++i) {
      double d;
      F64(&d, what);
    }
  }

 private:
  template <typename T>
  void Prim(T* v, size_t size, const char* what) {
    if (!ok()) return;
    if (cdr_ && !in_.Align(size)) return Fail(std::string(what) + ": truncated (alignment)");
    const size_t at = in_.pos() + offset_;
    bool got;
    if constexpr (std::is_same_v<T, uint32_t>) got = in_.U32(v);
    else if constexpr (std::is_same_v<T, int32_t>) got = in_.I32(v);
    else if constexpr (std::is_same_v<T, float>) got = in_.F32(v);
    else got = in_.F64(v);
    if (!got) Fail(std::string(what) + ": truncated at byte " + std::to_string(at));
  }
  void Fail(std::string msg) {
    if (error_.empty()) error_ = std::move(msg);
  }

  ByteCursor in_;
  bool cdr_;
  const char* type_;
  size_t offset_ = 0;
  std::string error_;
};

}  // namespace

Result<LaserScanMessage> DecodeLaserScan(std::string_view data, MessageEncoding encoding) {
  Decoder d(data, encoding, "sensor_msgs/LaserScan");
  LaserScanMessage m;
  d.Header(&m.stamp_ns, &m.frame_id);
  d.F32(&m.angle_min, "angle_min");
  d.F32(&m.angle_max, "angle_max");
  d.F32(&m.angle_increment, "angle_increment");
  d.F32(&m.time_increment, "time_increment");
  d.F32(&m.scan_time, "scan_time");
  d.F32(&m.range_min, "range_min");
  d.F32(&m.range_max, "range_max");
  d.Float32Array(&m.ranges, "ranges");
  if (!d.ok()) return d.status();
  return m;
}

Result<OdometryMessage> DecodeOdometry(std::string_view data, MessageEncoding encoding) {
  Decoder d(data, encoding, "nav_msgs/Odometry");
  OdometryMessage m;
  d.Header(&m.stamp_ns, &m.frame_id);
  d.String(&m.child_frame_id, "child_frame_id");
  d.Transform(&m.pose, "pose.pose");
  d.SkipF64(36, "pose.covariance");  // the twist after it is not needed
  if (!d.ok()) return d.status();
  return m;
}

Result<TfMessage> DecodeTfMessage(std::string_view data, MessageEncoding encoding) {
  Decoder d(data, encoding, "tf2_msgs/TFMessage");
  TfMessage m;
  // Smallest TransformStamped: stamp 8, two empty strings 8, 7 doubles 56.
  const uint32_t n = d.Count(72, "transforms");
  m.transforms.resize(n);
  for (uint32_t i = 0; i < n && d.ok(); ++i) {
    TransformStampedMessage& t = m.transforms[i];
    d.Header(&t.stamp_ns, &t.frame_id);
    d.String(&t.child_frame_id, "child_frame_id");
    d.Transform(&t.transform, "transform");
  }
  if (!d.ok()) return d.status();
  return m;
}

}  // namespace lmd

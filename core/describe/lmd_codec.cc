#include "core/describe/lmd_codec.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/util/byte_codec.h"

namespace lmd {
namespace {

constexpr size_t kFeatureBytesV1 = 14;
constexpr size_t kFeatureBytesV2 = 16;
constexpr uint16_t kNoInnerWord = 0xFFFF;

int16_t Quantise(float v) {
  const double q = std::round(static_cast<double>(v) / kLmdPositionQuantumM);
  if (!(q == q)) return 0;  // NaN
  if (q > 32767) return 32767;
  if (q < -32767) return -32767;
  return static_cast<int16_t>(q);
}

}  // namespace

std::string EncodeLmd(const Lmd& lmd) {
  std::string out;
  const bool inner = std::any_of(lmd.features.begin(), lmd.features.end(),
                                 [](const Feature& f) { return f.inner_word != kNoWord; });
  out.reserve(16 + (inner ? kFeatureBytesV2 : kFeatureBytesV1) * lmd.features.size());
  out.push_back(static_cast<char>(inner ? 2 : 1));
  PutVarint(out, lmd.features.size());
  PutF32(out, static_cast<float>(lmd.frame.origin.x));
  PutF32(out, static_cast<float>(lmd.frame.origin.y));
  PutF32(out, static_cast<float>(lmd.frame.heading));
  for (const Feature& f : lmd.features) {
    PutU16(out, static_cast<uint16_t>(Quantise(f.x)));
    PutU16(out, static_cast<uint16_t>(Quantise(f.y)));
    PutU16(out, static_cast<uint16_t>(f.appearance_word & 0xffff));
    if (inner) PutU16(out, f.inner_word == kNoWord ? kNoInnerWord : static_cast<uint16_t>(f.inner_word & 0x7fff));
    PutU64(out, f.change_word & ((uint64_t{1} << 60) - 1));
  }
  return out;
}

Result<Lmd> DecodeLmd(const std::string& bytes) {
  ByteReader r(bytes);
  uint8_t version;
  if (!r.U8(&version)) return Status::Corruption("lmd: empty record");
  if (version != 1 && version != 2) {
    return Status::Corruption("lmd: unknown format version " + std::to_string(version));
  }
  const size_t feature_bytes = version == 2 ? kFeatureBytesV2 : kFeatureBytesV1;
  uint64_t n;
  if (!r.Varint(&n)) return Status::Corruption("lmd: truncated feature count");
  Lmd lmd;
  float ox, oy, heading;
  if (!r.F32(&ox) || !r.F32(&oy) || !r.F32(&heading)) return Status::Corruption("lmd: truncated frame");
  if (!std::isfinite(ox) || !std::isfinite(oy) || !std::isfinite(heading)) {
    return Status::Corruption("lmd: non-finite frame");
  }
  if (n > r.left() / feature_bytes || n * feature_bytes != r.left()) {
    return Status::Corruption("lmd: " + std::to_string(n) + " features need " +
                              std::to_string(n * feature_bytes) + " bytes, record has " + std::to_string(r.left()));
  }
  lmd.frame = {{ox, oy}, heading};
  lmd.features.resize(static_cast<size_t>(n));
  for (Feature& f : lmd.features) {
    uint16_t x = 0, y = 0, w = 0, iw = kNoInnerWord;
    uint64_t cw = 0;
    r.U16(&x), r.U16(&y), r.U16(&w);
    if (version == 2) r.U16(&iw);
    r.U64(&cw);
    if (iw != kNoInnerWord && iw > 0x7fff) return Status::Corruption("lmd: inner word wider than 15 bits");
    if (cw >> 60) return Status::Corruption("lmd: change word wider than 60 bits");
    f.x = static_cast<float>(static_cast<int16_t>(x) * kLmdPositionQuantumM);
    f.y = static_cast<float>(static_cast<int16_t>(y) * kLmdPositionQuantumM);
    f.appearance_word = w;
    f.inner_word = iw == kNoInnerWord ? kNoWord : iw;
    f.change_word = cw;
  }
  return lmd;
}

}  // namespace lmd

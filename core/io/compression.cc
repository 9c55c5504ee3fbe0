#include "core/io/compression.h"

#include <bzlib.h>
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <memory>

namespace lmd {
namespace {

Status WrongSize(const std::string& what, const char* codec, uint64_t got, uint64_t expected, bool more) {
  return Status::Corruption(what + ": " + codec + " data decompresses to " + (more ? "more than " : "") +
                            std::to_string(got) + " bytes, the record says " + std::to_string(expected));
}

// Grows *out towards `expected`: doubling, from a start guessed from the input size.
void Grow(std::string* out, size_t produced, uint64_t expected, size_t in_size) {
  size_t next = std::max<size_t>(produced * 2, std::max<size_t>(in_size * 4, 1 << 16));
  next = static_cast<size_t>(std::min<uint64_t>(next, expected));
  out->resize(std::max(next, produced));
}

Status Zstd(std::string_view in, uint64_t expected, const std::string& what, std::string* out) {
  std::unique_ptr<ZSTD_DStream, size_t (*)(ZSTD_DStream*)> ds(ZSTD_createDStream(), ZSTD_freeDStream);
  if (!ds) return Status::ResourceExhausted(what + ": cannot allocate a zstd decoder");
  ZSTD_initDStream(ds.get());
  ZSTD_inBuffer input{in.data(), in.size(), 0};
  size_t produced = 0;
  size_t last = 1;  // 0 once a frame is complete
  while (true) {
    if (produced == out->size() && produced < expected) Grow(out, produced, expected, in.size());
    const bool probing = produced == out->size();  // full at the expected size: one more byte is too many
    char probe;
    ZSTD_outBuffer output = probing ? ZSTD_outBuffer{&probe, 1, 0} : ZSTD_outBuffer{out->data(), out->size(), produced};
    const size_t before_in = input.pos, before_out = output.pos;
    last = ZSTD_decompressStream(ds.get(), &output, &input);
    if (ZSTD_isError(last)) return Status::Corruption(what + ": zstd: " + ZSTD_getErrorName(last));
    if (probing && output.pos > 0) return WrongSize(what, "zstd", expected, expected, true);
    if (!probing) produced = output.pos;
    if (input.pos == input.size && (last == 0 || output.pos < output.size)) break;  // input used up, decoder drained
    if (input.pos == before_in && output.pos == before_out) break;
  }
  if (last != 0) return Status::Corruption(what + ": zstd data ends inside a frame (truncated chunk)");
  if (produced != expected) return WrongSize(what, "zstd", produced, expected, false);
  out->resize(produced);
  return Status::Ok();
}

Status Lz4(std::string_view in, uint64_t expected, const std::string& what, std::string* out) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
    return Status::ResourceExhausted(what + ": cannot allocate an lz4 decoder");
  }
  std::unique_ptr<LZ4F_dctx, LZ4F_errorCode_t (*)(LZ4F_dctx*)> ctx(raw, LZ4F_freeDecompressionContext);
  size_t consumed = 0, produced = 0;
  size_t hint = 1;  // 0 once a frame is complete
  while (true) {
    if (produced == out->size() && produced < expected) Grow(out, produced, expected, in.size());
    const bool probing = produced == out->size();
    char probe[16];
    size_t dst = probing ? sizeof(probe) : out->size() - produced;
    size_t src = in.size() - consumed;
    hint = LZ4F_decompress(ctx.get(), probing ? probe : out->data() + produced, &dst, in.data() + consumed, &src,
                           nullptr);
    if (LZ4F_isError(hint)) return Status::Corruption(what + ": lz4: " + LZ4F_getErrorName(hint));
    if (probing && dst > 0) return WrongSize(what, "lz4", expected, expected, true);
    if (!probing) produced += dst;
    consumed += src;
    if (hint == 0 && consumed == in.size()) break;  // every frame complete
    if (dst == 0 && src == 0) break;
  }
  if (hint != 0) return Status::Corruption(what + ": lz4 data ends inside a frame (truncated chunk)");
  if (produced != expected) return WrongSize(what, "lz4", produced, expected, false);
  out->resize(produced);
  return Status::Ok();
}

Status Bz2(std::string_view in, uint64_t expected, const std::string& what, std::string* out) {
  bz_stream strm{};
  if (BZ2_bzDecompressInit(&strm, 0, 0) != BZ_OK) return Status::ResourceExhausted(what + ": cannot start bzip2");
  struct End {
    bz_stream* s;
    ~End() { BZ2_bzDecompressEnd(s); }
  } end{&strm};
  strm.next_in = const_cast<char*>(in.data());
  strm.avail_in = static_cast<unsigned>(std::min<size_t>(in.size(), 0xffffffffu));
  size_t produced = 0;
  int ret = BZ_OK;
  while (ret != BZ_STREAM_END) {
    char probe[16];
    const bool full = produced == out->size();
    if (full && produced < expected) Grow(out, produced, expected, in.size());
    const bool probing = produced == out->size();  // full at the expected size
    strm.next_out = probing ? probe : out->data() + produced;
    const size_t room = probing ? sizeof(probe) : std::min<size_t>(out->size() - produced, 0xffffffffu);
    strm.avail_out = static_cast<unsigned>(room);
    const unsigned in_before = strm.avail_in;
    ret = BZ2_bzDecompress(&strm);
    if (ret != BZ_OK && ret != BZ_STREAM_END) {
      return Status::Corruption(what + ": bzip2 data is damaged (error " + std::to_string(ret) + ")");
    }
    const size_t got = room - strm.avail_out;
    if (probing && got > 0) return WrongSize(what, "bz2", expected, expected, true);
    if (!probing) produced += got;
    if (ret == BZ_OK && got == 0 && (strm.avail_in == 0 || strm.avail_in == in_before)) {
      return Status::Corruption(what + ": bzip2 data ends inside the stream (truncated chunk)");
    }
  }
  if (produced != expected) return WrongSize(what, "bz2", produced, expected, false);
  out->resize(produced);
  return Status::Ok();
}

}  // namespace

const char* CompressionName(Compression c) {
  switch (c) {
    case Compression::kNone: return "none";
    case Compression::kZstd: return "zstd";
    case Compression::kLz4Frame: return "lz4";
    case Compression::kBz2: return "bz2";
  }
  return "?";
}

Status Decompress(Compression compression, std::string_view in, uint64_t expected_size, uint64_t max_size,
                  const std::string& what, std::string* out) {
  out->clear();
  if (expected_size > max_size) {
    return Status::ResourceExhausted(what + ": declares " + std::to_string(expected_size) +
                                     " bytes uncompressed, more than the limit of " + std::to_string(max_size));
  }
  switch (compression) {
    case Compression::kNone:
      if (in.size() != expected_size) return WrongSize(what, "uncompressed", in.size(), expected_size, false);
      out->assign(in.data(), in.size());
      return Status::Ok();
    case Compression::kZstd: return Zstd(in, expected_size, what, out);
    case Compression::kLz4Frame: return Lz4(in, expected_size, what, out);
    case Compression::kBz2: return Bz2(in, expected_size, what, out);
  }
  return Status::Internal(what + ": unknown compression");
}

Status Compress(Compression compression, std::string_view in, std::string* out) {
  out->clear();
  switch (compression) {
    case Compression::kNone:
      out->assign(in.data(), in.size());
      return Status::Ok();
    case Compression::kZstd: {
      out->resize(ZSTD_compressBound(in.size()));
      const size_t n = ZSTD_compress(out->data(), out->size(), in.data(), in.size(), 3);
      if (ZSTD_isError(n)) return Status::Internal(std::string("zstd: ") + ZSTD_getErrorName(n));
      out->resize(n);
      return Status::Ok();
    }
    case Compression::kLz4Frame: {
      LZ4F_preferences_t prefs{};
      prefs.frameInfo.contentSize = in.size();
      out->resize(LZ4F_compressFrameBound(in.size(), &prefs));
      const size_t n = LZ4F_compressFrame(out->data(), out->size(), in.data(), in.size(), &prefs);
      if (LZ4F_isError(n)) return Status::Internal(std::string("lz4: ") + LZ4F_getErrorName(n));
      out->resize(n);
      return Status::Ok();
    }
    case Compression::kBz2: {
      unsigned int size = static_cast<unsigned int>(in.size() + in.size() / 100 + 600);
      out->resize(size);
      const int rc = BZ2_bzBuffToBuffCompress(out->data(), &size, const_cast<char*>(in.data()),
                                              static_cast<unsigned int>(in.size()), 9, 0, 0);
      if (rc != BZ_OK) return Status::Internal("bzip2: error " + std::to_string(rc));
      out->resize(size);
      return Status::Ok();
    }
  }
  return Status::Internal("unknown compression");
}

}  // namespace lmd

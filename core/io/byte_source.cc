#include "core/io/byte_source.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace lmd {
namespace {

Status Truncated(const std::string& name, uint64_t offset, uint64_t n, uint64_t size, const char* what) {
  return Status::Corruption(name + ": truncated at offset " + std::to_string(offset) + ": " + what + " needs " +
                            std::to_string(n) + " bytes, the file has " +
                            std::to_string(offset < size ? size - offset : 0) + " left");
}

class FileSource : public ByteSource {
 public:
  FileSource(int fd, uint64_t size, std::string name) : fd_(fd), size_(size), name_(std::move(name)) {}
  ~FileSource() override { ::close(fd_); }
  const std::string& name() const override { return name_; }
  uint64_t size() const override { return size_; }
  Status Read(uint64_t offset, uint64_t n, const char* what, std::string* out) const override {
    if (offset > size_ || n > size_ - offset) return Truncated(name_, offset, n, size_, what);
    out->resize(static_cast<size_t>(n));
    uint64_t done = 0;
    while (done < n) {
      const ssize_t got = ::pread(fd_, out->data() + done, static_cast<size_t>(n - done),
                                  static_cast<off_t>(offset + done));
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) return Status::IoError(name_ + ": read error at offset " + std::to_string(offset + done) +
                                          ": " + std::strerror(errno));
      if (got == 0) return Truncated(name_, offset, n, offset + done, what);  // shrank while open
      done += static_cast<uint64_t>(got);
    }
    return Status::Ok();
  }

 private:
  int fd_;
  uint64_t size_;
  std::string name_;
};

class BufferSource : public ByteSource {
 public:
  BufferSource(std::string bytes, std::string name) : bytes_(std::move(bytes)), name_(std::move(name)) {}
  const std::string& name() const override { return name_; }
  uint64_t size() const override { return bytes_.size(); }
  Status Read(uint64_t offset, uint64_t n, const char* what, std::string* out) const override {
    if (offset > bytes_.size() || n > bytes_.size() - offset) return Truncated(name_, offset, n, bytes_.size(), what);
    out->assign(bytes_, static_cast<size_t>(offset), static_cast<size_t>(n));
    return Status::Ok();
  }

 private:
  std::string bytes_;
  std::string name_;
};

}  // namespace

Result<std::unique_ptr<ByteSource>> OpenFileSource(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    const std::string msg = path + ": cannot open: " + std::strerror(err);
    return err == ENOENT ? Status::NotFound(msg) : Status::IoError(msg);
  }
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Status::IoError(path + ": not a regular file");
  }
  return std::unique_ptr<ByteSource>(new FileSource(fd, static_cast<uint64_t>(st.st_size), path));
}

std::unique_ptr<ByteSource> MemorySource(std::string bytes, std::string name) {
  return std::make_unique<BufferSource>(std::move(bytes), std::move(name));
}

}  // namespace lmd

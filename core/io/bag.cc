#include "core/io/bag.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/io/byte_source.h"
#include "core/io/mcap_reader.h"
#include "core/io/ros1_bag_reader.h"
#include "core/io/rosbag2_sqlite_reader.h"

namespace lmd {
namespace {

namespace fs = std::filesystem;

std::string Trim(std::string s) {
  const size_t b = s.find_first_not_of(" \t\r");
  const size_t e = s.find_last_not_of(" \t\r");
  s = b == std::string::npos ? "" : s.substr(b, e - b + 1);
  if (s.size() >= 2 && (s.front() == '\'' || s.front() == '"') && s.back() == s.front()) s = s.substr(1, s.size() - 2);
  return s;
}

// What a rosbag2 metadata.yaml says about its files: the keys lmd needs,
// read line by line (the file is written by rosbag2 in block style).
struct Rosbag2Metadata {
  std::vector<std::string> files;  // relative_file_paths
  std::string storage;             // storage_identifier
  std::string compression_format, compression_mode;
};

Rosbag2Metadata ReadMetadata(const std::string& text) {
  Rosbag2Metadata m;
  std::istringstream in(text);
  std::string line;
  size_t list_indent = std::string::npos;  // inside relative_file_paths when set
  while (std::getline(in, line)) {
    const size_t indent = line.find_first_not_of(' ');
    if (indent == std::string::npos || line[indent] == '#') continue;
    const std::string body = line.substr(indent);
    if (list_indent != std::string::npos) {
      if (indent >= list_indent && body.rfind("- ", 0) == 0) {
        m.files.push_back(Trim(body.substr(2)));
        continue;
      }
      list_indent = std::string::npos;
    }
    const size_t colon = body.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = body.substr(0, colon), value = Trim(body.substr(colon + 1));
    if (key == "relative_file_paths") list_indent = indent;
    else if (key == "storage_identifier") m.storage = value;
    else if (key == "compression_format") m.compression_format = value;
    else if (key == "compression_mode") m.compression_mode = value;
  }
  return m;
}

Result<std::unique_ptr<BagReader>> OpenFile(const std::string& path, const BagReadOptions& options) {
  Result<std::unique_ptr<ByteSource>> source = OpenFileSource(path);
  if (!source.ok()) return source.status();
  std::string head;
  Status s = (*source)->Read(0, std::min<uint64_t>((*source)->size(), 16), "the magic", &head);
  if (!s.ok()) return s;
  if (HasMcapMagic(head)) return OpenMcap(std::move(source).value(), options);
  if (HasRos1BagMagic(head) || head.rfind("#ROSBAG V", 0) == 0) return OpenRos1Bag(std::move(source).value(), options);
  if (HasSqliteMagic(head)) return OpenRosbag2Sqlite(path);
  std::string shown;
  for (unsigned char c : head.substr(0, 8)) {
    char buf[4];
    std::snprintf(buf, sizeof buf, "%02x", c);
    shown += buf;
  }
  return Status::InvalidArgument(path + ": not a bag: its first bytes (" + (shown.empty() ? "none" : shown) +
                                 ") are neither MCAP's, a ROS 1 bag v2.0's nor SQLite's magic");
}

// The files of a multi-file rosbag2 bag, read one after the other as one bag.
class SplitBag : public BagReader {
 public:
  SplitBag(std::string path, std::vector<std::unique_ptr<BagReader>> parts)
      : path_(std::move(path)), parts_(std::move(parts)) {
    for (auto& part : parts_) {
      std::vector<size_t> mapping;
      for (const BagTopic& t : part->topics()) mapping.push_back(topics_.Add(t.name, t.type, t.encoding_name, t.message_count));
      maps_.push_back(std::move(mapping));
    }
  }
  const std::string& path() const override { return path_; }
  std::string format() const override {
    return "rosbag2 directory of " + std::to_string(parts_.size()) + " files (" + parts_[0]->format() + ")";
  }
  const std::vector<BagTopic>& topics() const override { return topics_.topics(); }
  Status ReadMessages(const std::vector<size_t>& wanted,
                      const std::function<Status(const BagMessage&)>& on_message) override {
    for (size_t p = 0; p < parts_.size(); ++p) {
      std::vector<size_t> local;
      for (size_t i = 0; i < maps_[p].size(); ++i) {
        if (std::find(wanted.begin(), wanted.end(), maps_[p][i]) != wanted.end()) local.push_back(i);
      }
      const std::vector<size_t>& mapping = maps_[p];
      Status s = parts_[p]->ReadMessages(local, [&](const BagMessage& m) {
        BagMessage out = m;
        out.topic = mapping[m.topic];
        out.where = parts_[p]->path() + " " + m.where;
        return on_message(out);
      });
      if (!s.ok()) return s;
    }
    return Status::Ok();
  }

 private:
  std::string path_;
  std::vector<std::unique_ptr<BagReader>> parts_;
  std::vector<std::vector<size_t>> maps_;  // per part: its topic index -> ours
  TopicTable topics_;
};

Result<std::unique_ptr<BagReader>> OpenDirectory(const std::string& dir, const BagReadOptions& options) {
  std::vector<std::string> files;
  const fs::path meta_path = fs::path(dir) / "metadata.yaml";
  std::error_code ec;
  if (fs::exists(meta_path, ec)) {
    std::ifstream in(meta_path);
    std::stringstream text;
    text << in.rdbuf();
    const Rosbag2Metadata meta = ReadMetadata(text.str());
    if (!meta.compression_format.empty()) {
      return Status::InvalidArgument(meta_path.string() + ": the bag is compressed by rosbag2 (" +
                                     meta.compression_format + ", mode " + meta.compression_mode +
                                     "), which lmd does not read: decompress it first (ros2 bag convert)");
    }
    for (const std::string& f : meta.files) files.push_back((fs::path(dir) / f).string());
  }
  if (files.empty()) {  // no metadata (or none listing files): the directory's bag files by name
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      const std::string ext = entry.path().extension().string();
      if (entry.is_regular_file() && (ext == ".db3" || ext == ".mcap" || ext == ".bag")) {
        files.push_back(entry.path().string());
      }
    }
    std::sort(files.begin(), files.end());
  }
  if (files.empty()) {
    return Status::InvalidArgument(dir + ": a directory without a bag (no metadata.yaml listing files, no .db3, "
                                         ".mcap or .bag file)");
  }
  std::vector<std::unique_ptr<BagReader>> parts;
  for (const std::string& f : files) {
    Result<std::unique_ptr<BagReader>> part = OpenFile(f, options);
    if (!part.ok()) return part.status();
    parts.push_back(std::move(part).value());
  }
  if (parts.size() == 1) return std::move(parts[0]);
  return std::unique_ptr<BagReader>(new SplitBag(dir, std::move(parts)));
}

}  // namespace

size_t TopicTable::Add(const std::string& name, const std::string& type, const std::string& encoding_name,
                       uint64_t count) {
  auto [it, added] = by_key_.emplace(name + '\0' + type, topics_.size());
  if (added) {
    BagTopic t;
    t.name = name;
    t.type = type;
    t.encoding_name = encoding_name;
    t.encoding = encoding_name == "cdr" ? MessageEncoding::kCdr
                 : encoding_name == "ros1" ? MessageEncoding::kRos1 : MessageEncoding::kOther;
    topics_.push_back(std::move(t));
  }
  topics_[it->second].message_count += count;
  return it->second;
}

Result<std::unique_ptr<BagReader>> OpenBag(const std::string& path, const BagReadOptions& options) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return Status::NotFound(path + ": no such file or directory");
  if (fs::is_directory(st)) return OpenDirectory(path, options);
  return OpenFile(path, options);
}

std::string CanonicalType(const std::string& type) {
  std::string t = type;
  const size_t msg = t.find("/msg/");
  if (msg != std::string::npos) t.erase(msg, 4);
  if (t == "tf/tfMessage") t = "tf2_msgs/TFMessage";
  return t;
}

}  // namespace lmd

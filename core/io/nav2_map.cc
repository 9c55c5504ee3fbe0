#include "core/io/nav2_map.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

namespace lmd {
namespace {

constexpr int64_t kMaxCells = 400000000;  // 20 km x 20 km at 1 m; real maps are far smaller

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

std::string Unquote(std::string s) {
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) s = s.substr(1, s.size() - 2);
  return s;
}

bool Number(const std::string& text, double* v) {
  const std::string t = Trim(text);
  char* end = nullptr;
  *v = std::strtod(t.c_str(), &end);
  return !t.empty() && *end == '\0' && std::isfinite(*v);
}

// The top-level "key: value" lines of a map YAML ('#' comments dropped).
std::map<std::string, std::string> FlatYaml(const std::string& text) {
  std::map<std::string, std::string> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos && (hash == 0 || line[hash - 1] == ' ' || line[hash - 1] == '\t')) line.resize(hash);
    if (line.empty() || line[0] == ' ' || line[0] == '\t') continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    out[Trim(line.substr(0, colon))] = Trim(line.substr(colon + 1));
  }
  return out;
}

// A PGM's next header token (comments skipped).
bool Token(const std::string& bytes, size_t* at, std::string* tok) {
  tok->clear();
  while (*at < bytes.size()) {
    const char c = bytes[*at];
    if (c == '#') {
      while (*at < bytes.size() && bytes[*at] != '\n') ++*at;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++*at;
    } else {
      break;
    }
  }
  while (*at < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[*at])) && bytes[*at] != '#') {
    tok->push_back(bytes[(*at)++]);
  }
  return !tok->empty();
}

Status ReadFile(const std::string& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::NotFound(path + ": cannot open");
  out->assign(std::istreambuf_iterator<char>(in), {});
  if (in.bad()) return Status::IoError(path + ": read error");
  return Status::Ok();
}

struct Gray {
  int width = 0, height = 0, maxval = 255;
  std::vector<uint16_t> pixels;  // row-major, top row first
};

Result<Gray> ReadPgm(const std::string& path) {
  std::string bytes;
  Status s = ReadFile(path, &bytes);
  if (!s.ok()) return s;
  if (bytes.size() < 2 || bytes[0] != 'P' || (bytes[1] != '5' && bytes[1] != '2')) {
    return Status::InvalidArgument(path + ": not a PGM image (P5 or P2): lmd reads map_server maps saved as PGM");
  }
  const bool binary = bytes[1] == '5';
  size_t at = 2;
  std::string w, h, m;
  long values[3] = {0, 0, 0};
  if (!Token(bytes, &at, &w) || !Token(bytes, &at, &h) || !Token(bytes, &at, &m)) {
    return Status::InvalidArgument(path + ": PGM header is cut short");
  }
  const std::string* toks[3] = {&w, &h, &m};
  for (int i = 0; i < 3; ++i) {
    char* end = nullptr;
    values[i] = std::strtol(toks[i]->c_str(), &end, 10);
    if (*end != '\0' || values[i] <= 0) return Status::InvalidArgument(path + ": PGM header holds '" + *toks[i] + "'");
  }
  Gray g;
  g.width = static_cast<int>(std::min<long>(values[0], INT32_MAX));
  g.height = static_cast<int>(std::min<long>(values[1], INT32_MAX));
  g.maxval = static_cast<int>(std::min<long>(values[2], 70000));
  if (g.maxval > 65535) return Status::InvalidArgument(path + ": PGM maxval " + m + " is over 65535");
  const int64_t n = static_cast<int64_t>(g.width) * g.height;
  if (values[0] > INT32_MAX || values[1] > INT32_MAX || n > kMaxCells) {
    return Status::InvalidArgument(path + ": PGM of " + w + " x " + h + " pixels is larger than lmd reads");
  }
  const int sample = g.maxval > 255 ? 2 : 1;
  if (binary) {
    ++at;  // the single whitespace after maxval
    if (bytes.size() < at || static_cast<uint64_t>(bytes.size() - at) < static_cast<uint64_t>(n) * sample) {
      return Status::InvalidArgument(path + ": PGM is cut short: " + std::to_string(n) + " pixels declared, " +
                                     std::to_string((bytes.size() - std::min(at, bytes.size())) / sample) + " present");
    }
    g.pixels.resize(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) {
      const unsigned char* p = reinterpret_cast<const unsigned char*>(bytes.data() + at + i * sample);
      g.pixels[static_cast<size_t>(i)] = static_cast<uint16_t>(sample == 2 ? (p[0] << 8) | p[1] : p[0]);
    }
  } else {
    if (static_cast<uint64_t>(n) > bytes.size()) return Status::InvalidArgument(path + ": PGM is cut short");
    g.pixels.reserve(static_cast<size_t>(n));
    std::string tok;
    for (int64_t i = 0; i < n; ++i) {
      if (!Token(bytes, &at, &tok)) return Status::InvalidArgument(path + ": PGM is cut short at pixel " + std::to_string(i));
      g.pixels.push_back(static_cast<uint16_t>(std::min<long>(std::strtol(tok.c_str(), nullptr, 10), g.maxval)));
    }
  }
  return g;
}

}  // namespace

Point2 OccupancyMap::CellCentre(int ix, int iy) const {
  const double lx = (ix + 0.5) * resolution, ly = (iy + 0.5) * resolution;
  const double c = std::cos(origin.theta), s = std::sin(origin.theta);
  return {origin.x + c * lx - s * ly, origin.y + s * lx + c * ly};
}

Result<OccupancyMap> ReadNav2Map(const std::string& yaml_path) {
  std::string text;
  Status s = ReadFile(yaml_path, &text);
  if (!s.ok()) return s;
  const std::map<std::string, std::string> yaml = FlatYaml(text);
  auto missing = [&](const char* key) { return Status::InvalidArgument(yaml_path + ": no '" + key + "' key"); };
  auto bad = [&](const char* key) {
    return Status::InvalidArgument(yaml_path + ": '" + key + "' is not what map_server expects: '" + yaml.at(key) + "'");
  };
  for (const char* key : {"image", "resolution", "origin", "occupied_thresh", "free_thresh"}) {
    if (!yaml.count(key)) return missing(key);
  }
  OccupancyMap map;
  double occupied = 0, free = 0;
  if (!Number(yaml.at("resolution"), &map.resolution) || !(map.resolution > 0)) return bad("resolution");
  if (!Number(yaml.at("occupied_thresh"), &occupied)) return bad("occupied_thresh");
  if (!Number(yaml.at("free_thresh"), &free)) return bad("free_thresh");
  std::string origin = yaml.at("origin");
  if (origin.size() < 2 || origin.front() != '[' || origin.back() != ']') return bad("origin");
  std::vector<double> o;
  std::stringstream parts(origin.substr(1, origin.size() - 2));
  for (std::string part; std::getline(parts, part, ',');) {
    double v = 0;
    if (!Number(part, &v)) return bad("origin");
    o.push_back(v);
  }
  if (o.size() != 3) return bad("origin");
  map.origin = {o[0], o[1], o[2]};
  bool negate = false;
  if (yaml.count("negate")) {
    const std::string n = yaml.at("negate");
    if (n == "1" || n == "true" || n == "True") negate = true;
    else if (n != "0" && n != "false" && n != "False") return bad("negate");
  }
  const std::string mode = yaml.count("mode") ? Unquote(yaml.at("mode")) : "trinary";
  if (mode != "trinary" && mode != "scale" && mode != "raw") return bad("mode");
  std::string image = Unquote(yaml.at("image"));
  if (image.empty()) return bad("image");
  if (image[0] != '/') {
    const size_t slash = yaml_path.find_last_of('/');
    image = (slash == std::string::npos ? std::string(".") : yaml_path.substr(0, slash)) + "/" + image;
  }
  Result<Gray> gray = ReadPgm(image);
  if (!gray.ok()) return gray.status();
  map.width = gray->width;
  map.height = gray->height;
  map.cells.resize(gray->pixels.size());
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const double value = gray->pixels[static_cast<size_t>(y) * map.width + x];
      const double shade = value / gray->maxval;
      const double occ = negate ? shade : 1.0 - shade;
      int8_t cell;
      if (mode == "raw") {
        const double v = std::round(shade * 255);
        cell = v >= 0 && v <= 100 ? static_cast<int8_t>(v) : OccupancyMap::kUnknown;
      } else if (occupied < occ) {
        cell = OccupancyMap::kOccupied;
      } else if (occ < free) {
        cell = OccupancyMap::kFree;
      } else if (mode == "scale") {
        cell = static_cast<int8_t>(std::rint((occ - free) / (occupied - free) * 100.0));
      } else {
        cell = OccupancyMap::kUnknown;
      }
      map.cells[static_cast<size_t>(map.height - y - 1) * map.width + x] = cell;  // image top = map top
    }
  }
  return map;
}

Status WriteNav2Map(const std::string& yaml_path, const OccupancyMap& map) {
  std::string stem = yaml_path;
  if (stem.size() > 5 && stem.compare(stem.size() - 5, 5, ".yaml") == 0) stem.resize(stem.size() - 5);
  const std::string pgm = stem + ".pgm";
  std::string bytes = "P5\n# lmd export-map\n" + std::to_string(map.width) + " " + std::to_string(map.height) + "\n255\n";
  const size_t header = bytes.size();
  bytes.resize(header + static_cast<size_t>(map.width) * map.height);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const int8_t c = map.cells[static_cast<size_t>(map.height - y - 1) * map.width + x];
      const unsigned char pixel = c < 0 || c > 100 ? 205 : c <= 19 ? 254 : c >= 65 ? 0 : 205;
      bytes[header + static_cast<size_t>(y) * map.width + x] = static_cast<char>(pixel);
    }
  }
  {
    std::ofstream out(pgm, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) return Status::IoError(pgm + ": cannot write");
  }
  char origin[128];
  std::snprintf(origin, sizeof origin, "[%.6f, %.6f, %.6f]", map.origin.x, map.origin.y, map.origin.theta);
  std::ofstream yaml(yaml_path, std::ios::trunc);
  yaml << "image: " << pgm.substr(pgm.find_last_of('/') + 1) << "\nmode: trinary\nresolution: " << map.resolution
       << "\norigin: " << origin << "\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  if (!yaml) return Status::IoError(yaml_path + ": cannot write");
  return Status::Ok();
}

}  // namespace lmd

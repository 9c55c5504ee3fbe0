#include "core/index/pyramid_kernel.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace lmd {
namespace {

static_assert((-3 >> 1) == -2, "cells use arithmetic right shifts as floor division by 2^k");

// Up to 64 x 64 offset bins are counted in an array (3 m box, 0.5 m bins:
// 13 x 13); wider boxes sort the matches instead.
constexpr int32_t kMaxCountedBinsPerAxis = 64;

bool PoseFeatureLess(const PoseFeature& a, const PoseFeature& b) {
  if (a.word != b.word) return a.word < b.word;
  if (a.x != b.x) return a.x < b.x;
  return a.y < b.y;
}

// Lexicographic (a, b) as one int64.
int64_t PackPair(int32_t a, int32_t b) {
  return static_cast<int64_t>(a) * (int64_t{1} << 32) + (static_cast<int64_t>(b) + (int64_t{1} << 31));
}

// Pairs the query and db features that share an appearance word.
void GroupSharedWords(const PreparedLmdQuery& q, const PoseFeature* db, size_t nd,
                      std::vector<KernelScratch::Group>* groups) {
  groups->clear();
  const PoseFeature* qf = q.features.data();
  const size_t nq = q.features.size();
  size_t i = 0, j = 0;
  while (i < nq && j < nd) {
    if (qf[i].word < db[j].word) {
      ++i;
    } else if (db[j].word < qf[i].word) {
      ++j;
    } else {
      const uint32_t w = qf[i].word;
      size_t ie = i + 1, je = j + 1;
      while (ie < nq && qf[ie].word == w) ++ie;
      while (je < nd && db[je].word == w) ++je;
      groups->push_back({static_cast<uint32_t>(i), static_cast<uint32_t>(ie), static_cast<uint32_t>(j),
                         static_cast<uint32_t>(je)});
      i = ie;
      j = je;
    }
  }
}

}  // namespace

Result<std::vector<PoseFeature>> ToPoseFeatures(const Lmd& lmd, const IndexOptions& options) {
  std::vector<PoseFeature> out;
  out.reserve(lmd.features.size());
  const double inv = 1.0 / options.pose_quantum_m;
  for (size_t i = 0; i < lmd.features.size(); ++i) {
    const Feature& f = lmd.features[i];
    if (f.appearance_word > kMaxAppearanceWord)
      return Status::InvalidArgument("feature " + std::to_string(i) + ": appearance word " +
                                     std::to_string(f.appearance_word) + " exceeds 65535");
    const bool inner = f.inner_word != kNoWord;
    if (inner && (f.appearance_word >= kInnerWordTag || f.inner_word >= kInnerWordTag))
      return Status::InvalidArgument("feature " + std::to_string(i) +
                                     ": a feature with an inner word needs words below 32768");
    const double x = std::round(f.x * inv), y = std::round(f.y * inv);
    if (!std::isfinite(x) || !std::isfinite(y) || std::fabs(x) > 32767 || std::fabs(y) > 32767)
      return Status::InvalidArgument("feature " + std::to_string(i) +
                                     ": position is not finite or outside the pose-word range");
    out.push_back({f.appearance_word, static_cast<int16_t>(x), static_cast<int16_t>(y)});
    if (inner) out.push_back({f.inner_word | kInnerWordTag, static_cast<int16_t>(x), static_cast<int16_t>(y)});
  }
  std::sort(out.begin(), out.end(), PoseFeatureLess);
  return out;
}

size_t PoseFeatureCount(const Lmd& lmd) {
  return lmd.features.size() + static_cast<size_t>(std::count_if(lmd.features.begin(), lmd.features.end(),
                                                                 [](const Feature& f) { return f.inner_word != kNoWord; }));
}

FloorDivider::FloorDivider(int32_t d) : d_(d) {
  int log2d = 0;
  while ((int64_t{1} << log2d) < d) ++log2d;
  constexpr int kBits = 19;  // x + bias < 2^19
  shift_ = kBits + log2d;
  magic_ = ((uint64_t{1} << shift_) + static_cast<uint64_t>(d) - 1) / static_cast<uint64_t>(d);
  bias_cells_ = (1 << 17) / d + 1;
  bias_ = bias_cells_ * d;
  limit_ = (1 << 17);
}

std::vector<PoseFeature> WithoutStopWords(std::vector<PoseFeature> features, const std::vector<uint32_t>& stop_words) {
  if (stop_words.empty()) return features;
  features.erase(std::remove_if(features.begin(), features.end(),
                                [&](const PoseFeature& f) {
                                  return std::binary_search(stop_words.begin(), stop_words.end(), f.word);
                                }),
                 features.end());
  return features;
}

PreparedLmdQuery PrepareLmdQuery(std::vector<PoseFeature> query, const IndexOptions& index_options,
                           const RetrieveOptions& options) {
  PreparedLmdQuery q;
  q.features = std::move(query);
  const size_t n = q.features.size();
  for (int o = 0; o < 4; ++o) {
    q.rx[o].resize(n);
    q.ry[o].resize(n);
  }
  for (size_t i = 0; i < n; ++i) {
    const int32_t x = q.features[i].x, y = q.features[i].y;
    q.rx[0][i] = x;  q.ry[0][i] = y;
    q.rx[1][i] = -y; q.ry[1][i] = x;
    q.rx[2][i] = -x; q.ry[2][i] = -y;
    q.rx[3][i] = y;  q.ry[3][i] = -x;
  }
  // Floor so that the box is never wider than asked; the bin is at least 1 unit.
  q.max_offset = static_cast<int32_t>(std::floor(options.max_offset_m / index_options.pose_quantum_m + 1e-9));
  q.offset_bin = std::min<int32_t>(
      30000, std::max<int32_t>(1, static_cast<int32_t>(std::lround(options.offset_bin_m / index_options.pose_quantum_m))));
  q.cell0 = static_cast<int32_t>(std::lround(index_options.pyramid_cell_m / index_options.pose_quantum_m));
  q.levels = index_options.pyramid_levels;
  q.normalization = options.normalization;
  q.fine_div = FloorDivider(q.cell0 >> q.levels);
  q.bin_div = FloorDivider(q.offset_bin);
  q.bin_lo = q.bin_div(-q.max_offset);
  const int32_t bins = q.bin_div(q.max_offset) - q.bin_lo + 1;
  q.bins = bins <= kMaxCountedBinsPerAxis ? bins : 0;
  for (int o = 0; o < 4; ++o) {
    q.order[o].resize(n);
    for (size_t i = 0; i < n; ++i) q.order[o][i] = static_cast<uint32_t>(i);
    const auto& rxo = q.rx[o];
    std::sort(q.order[o].begin(), q.order[o].end(), [&](uint32_t a, uint32_t b) {
      if (q.features[a].word != q.features[b].word) return q.features[a].word < q.features[b].word;
      return rxo[a] < rxo[b];
    });
  }
  return q;
}

double NormalizeScore(double raw, size_t nq, size_t nd, Normalization normalization) {
  if (nq == 0 || nd == 0) return 0.0;
  switch (normalization) {
    case Normalization::kNone: return raw;
    case Normalization::kMin: return raw / static_cast<double>(std::min(nq, nd));
    case Normalization::kSqrt: return raw / std::sqrt(static_cast<double>(nq) * static_cast<double>(nd));
  }
  return raw;
}

KernelScore ScoreLmdMap(const PreparedLmdQuery& q, const PoseFeature* db, size_t nd, KernelScratch* s,
                        unsigned orientations) {
  KernelScore best;
  GroupSharedWords(q, db, nd, &s->groups);
  if (s->groups.empty()) return best;
  const int32_t box = q.max_offset;
  const int levels = q.levels;
  const size_t nl = static_cast<size_t>(levels) + 1;
  // Level-l cell = finest cell >> (L - l): cells nest, one division per axis.
  // Db cells of the groups that are not one-to-one, sorted per level (they do
  // not depend on the orientation or the offset).
  s->multi.clear();
  s->cells.clear();
  s->offsets.clear();
  s->run.clear();
  for (uint32_t g = 0; g < s->groups.size(); ++g) {
    const auto& gr = s->groups[g];
    if (gr.q_end - gr.q_begin == 1 && gr.d_end - gr.d_begin == 1) continue;
    s->multi.push_back(g);
    for (int l = 0; l <= levels; ++l) {
      const size_t begin = s->cells.size();
      s->offsets.push_back(static_cast<uint32_t>(begin));
      for (uint32_t j = gr.d_begin; j < gr.d_end; ++j)
        s->cells.push_back(PackPair(q.fine_div(db[j].x) >> (levels - l), q.fine_div(db[j].y) >> (levels - l)));
      std::sort(s->cells.begin() + static_cast<long>(begin), s->cells.end());
      // Keep distinct cells, their counts in run.
      const size_t n = s->cells.size();
      if (s->run.size() < n) s->run.resize(n);
      int64_t* cells = s->cells.data();
      size_t out = begin;
      for (size_t a = begin; a < n;) {
        size_t b = a + 1;
        while (b < n && cells[b] == cells[a]) ++b;
        cells[out] = cells[a];
        s->run[out] = static_cast<uint32_t>(b - a);
        ++out;
        a = b;
      }
      s->cells.resize(out);
    }
  }
  s->offsets.push_back(static_cast<uint32_t>(s->cells.size()));
  for (int o = 0; o < 4; ++o) {
    if ((orientations >> o & 1u) == 0) continue;
    const int32_t* rx = q.rx[o].data();
    const int32_t* ry = q.ry[o].data();
    // 1-3: matches in the box, histogram of differences, mode bin, offset.
    s->matches.clear();
    const uint32_t* order = q.order[o].data();
    for (const auto& g : s->groups) {
      // Query features in increasing rotated x against db features sorted by
      // x: a window [x - box, x + box] that only moves forward.
      uint32_t start = g.d_begin;
      for (uint32_t k = g.q_begin; k < g.q_end; ++k) {
        const uint32_t i = order[k];
        while (start < g.d_end && db[start].x < rx[i] - box) ++start;
        for (uint32_t j = start; j < g.d_end && db[j].x <= rx[i] + box; ++j) {
          const int32_t dx = db[j].x - rx[i], dy = db[j].y - ry[i];
          if (dy < -box || dy > box) continue;
          // Bin ids ordered as (bin x, bin y) pairs, so both ways below pick the same mode.
          const int64_t bin = q.bins ? int64_t{q.bin_div(dx) - q.bin_lo} * q.bins + (q.bin_div(dy) - q.bin_lo)
                                     : PackPair(q.bin_div(dx), q.bin_div(dy));
          s->matches.push_back({bin, dx, dy});
        }
      }
    }
    if (s->matches.empty()) continue;
    // Mode bin: the most matches, the smallest bin id among equals.
    int64_t mode = 0;
    size_t mode_count = 0;
    if (q.bins) {
      // Counted as the matches come (the first bin to reach a count, or a
      // smaller one reaching it later, is the mode), then the touched bins
      // are zeroed again: far fewer steps than the bins x bins array.
      if (s->bin_counts.size() < static_cast<size_t>(q.bins) * q.bins) {
        s->bin_counts.assign(static_cast<size_t>(q.bins) * q.bins, 0);
      }
      for (const KernelScratch::Match& m : s->matches) {
        const size_t count = ++s->bin_counts[m.bin];
        if (count > mode_count || (count == mode_count && m.bin < mode)) mode_count = count, mode = m.bin;
      }
      for (const KernelScratch::Match& m : s->matches) s->bin_counts[m.bin] = 0;
    } else {
      std::sort(s->matches.begin(), s->matches.end(),
                [](const KernelScratch::Match& a, const KernelScratch::Match& b) { return a.bin < b.bin; });
      for (size_t k = 0; k < s->matches.size();) {
        size_t e = k + 1;
        while (e < s->matches.size() && s->matches[e].bin == s->matches[k].bin) ++e;
        if (e - k > mode_count) mode_count = e - k, mode = s->matches[k].bin;
        k = e;
      }
    }
    int64_t sx = 0, sy = 0;
    for (const KernelScratch::Match& m : s->matches) {
      if (m.bin == mode) sx += m.dx, sy += m.dy;
    }
    const int64_t c = static_cast<int64_t>(mode_count);
    // round(sum / c), halves toward +inf; exact integer arithmetic.
    auto round_mean = [c](int64_t sum) {
      const int64_t num = 2 * sum + c, den = 2 * c;
      return static_cast<int32_t>(num >= 0 ? num / den : -((-num + den - 1) / den));
    };
    const int32_t tx = round_mean(sx), ty = round_mean(sy);
    // 4-5: pyramid intersection of the shifted query against the db map.
    int inter[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    for (const auto& g : s->groups) {
      if (g.q_end - g.q_begin != 1 || g.d_end - g.d_begin != 1) continue;
      const int32_t qx = q.fine_div(rx[g.q_begin] + tx), qy = q.fine_div(ry[g.q_begin] + ty);
      const int32_t px = q.fine_div(db[g.d_begin].x), py = q.fine_div(db[g.d_begin].y);
      for (int l = 0; l <= levels; ++l) {
        const int shift = levels - l;
        if ((qx >> shift) != (px >> shift) || (qy >> shift) != (py >> shift)) break;
        ++inter[l];
      }
    }
    // Other groups: each query feature takes one unmatched db feature of its
    // cell, so the count is sum over cells of min(query count, db count).
    s->used.assign(s->cells.size(), 0);
    for (size_t k = 0; k < s->multi.size(); ++k) {
      const auto& g = s->groups[s->multi[k]];
      for (uint32_t i = g.q_begin; i < g.q_end; ++i) {
        const int32_t fx = q.fine_div(rx[i] + tx), fy = q.fine_div(ry[i] + ty);
        for (int l = 0; l <= levels; ++l) {
          const int64_t* begin = s->cells.data() + s->offsets[k * nl + static_cast<size_t>(l)];
          const int64_t* end = s->cells.data() + s->offsets[k * nl + static_cast<size_t>(l) + 1];
          const int64_t cell = PackPair(fx >> (levels - l), fy >> (levels - l));
          const int64_t* run = std::lower_bound(begin, end, cell);
          // Cells nest: no db feature in this cell, none in its finer cells.
          if (run == end || *run != cell) break;
          const size_t first = static_cast<size_t>(run - s->cells.data());
          if (s->used[first] < s->run[first]) {
            ++s->used[first];
            ++inter[l];
          }
        }
      }
    }
    double raw = std::ldexp(static_cast<double>(inter[0]), -levels);
    for (int l = 1; l <= levels; ++l) raw += std::ldexp(static_cast<double>(inter[l]), -(levels - l + 1));
    const double score = NormalizeScore(raw, q.features.size(), nd, q.normalization);
    if (score > best.score) best = {score, o, tx, ty};
  }
  return best;
}

double ScoreBowMap(const PreparedLmdQuery& q, const PoseFeature* db, size_t nd) {
  const PoseFeature* qf = q.features.data();
  const size_t nq = q.features.size();
  size_t i = 0, j = 0;
  int64_t total = 0;
  while (i < nq && j < nd) {
    if (qf[i].word < db[j].word) {
      ++i;
    } else if (db[j].word < qf[i].word) {
      ++j;
    } else {
      const uint32_t w = qf[i].word;
      int64_t a = 0, b = 0;
      while (i < nq && qf[i].word == w) ++i, ++a;
      while (j < nd && db[j].word == w) ++j, ++b;
      total += std::min(a, b);
    }
  }
  return NormalizeScore(static_cast<double>(total), nq, nd, q.normalization);
}

}  // namespace lmd

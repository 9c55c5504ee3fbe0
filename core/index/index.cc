#include "core/index/index.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/index/top_hits.h"

namespace lmd {
namespace {

constexpr uint32_t kNoSlot = std::numeric_limits<uint32_t>::max();

// Per-thread counters indexed by slot, kept all-zero between queries.
struct RetrieveScratch {
  std::vector<uint32_t> counts;   // 4 per slot (kLmd bound) or 1 per slot (kBow)
  std::vector<uint32_t> touched;
  std::vector<uint32_t> word_touched;
  std::vector<uint32_t> word_counts;
  std::vector<uint32_t> bounds;  // kLmd pass 1: 4 per slot, 2^L * raw K bound per orientation
  std::vector<uint32_t> tables;  // kLmd pass 1: per list read, see RetrieveLmd
  std::vector<uint32_t> term_gains;
  std::vector<uint64_t> term_masks;
  std::vector<uint8_t> term_o;
  KernelScratch kernel;
};

RetrieveScratch& Scratch() {
  thread_local RetrieveScratch scratch;
  return scratch;
}

// The level-0 cell of a posting key (PostingKey).
int32_t CellX(uint64_t key) { return static_cast<int16_t>((key >> 16) & 0xFFFF); }
int32_t CellY(uint64_t key) { return static_cast<int16_t>(key & 0xFFFF); }

}  // namespace

Index::Index(const IndexOptions& options) : options_(options) {
  cell0_ = static_cast<int32_t>(std::lround(options.pyramid_cell_m / options.pose_quantum_m));
}

Result<Index> Index::Create(const IndexOptions& options) {
  Status st = ValidateIndexOptions(options);
  if (!st.ok()) return st;
  return Index(options);
}

uint64_t Index::PostingKey(uint32_t word, int32_t cx, int32_t cy) {
  return (static_cast<uint64_t>(word) << 32) | (static_cast<uint64_t>(static_cast<uint16_t>(cx)) << 16) |
         static_cast<uint64_t>(static_cast<uint16_t>(cy));
}

Status Index::Add(uint64_t id, const Lmd& lmd) {
  if (Contains(id)) return Status::AlreadyExists("map " + std::to_string(id) + " is already indexed");
  auto features = ToPoseFeatures(lmd, options_);
  if (!features.ok()) return features.status();
  return AddPoseFeatures(id, std::move(features).value());
}

Status Index::AddPoseFeatures(uint64_t id, std::vector<PoseFeature> features) {
  if (Contains(id)) return Status::AlreadyExists("map " + std::to_string(id) + " is already indexed");
  for (size_t i = 0; i < features.size(); ++i) {
    if (features[i].word > kMaxAppearanceWord)
      return Status::InvalidArgument("appearance word exceeds 65535");
    if (i > 0) {
      const PoseFeature& a = features[i - 1];
      const PoseFeature& b = features[i];
      if (a.word > b.word || (a.word == b.word && (a.x > b.x || (a.x == b.x && a.y > b.y))))
        return Status::InvalidArgument("pose features are not sorted by (word, x, y)");
    }
  }
  uint32_t slot;
  if (free_slots_.empty() && slot_id_.size() >= kMaxMaps)
    return Status::ResourceExhausted("an index holds at most 16777215 maps");
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
  } else {
    slot = static_cast<uint32_t>(slot_id_.size());
    slot_id_.push_back(0);
    slot_used_.push_back(0);
    slot_features_.emplace_back();
  }
  for (const PoseFeature& f : features) {
    const uint64_t key = PostingKey(f.word, FloorDiv(f.x, cell0_), FloorDiv(f.y, cell0_));
    auto [it, inserted] = lists_.try_emplace(key);
    if (inserted) word_lists_[f.word].push_back({key, &it->second});
    ++word_postings_[f.word];
    const int32_t fine = cell0_ >> options_.pyramid_levels, side = 1 << options_.pyramid_levels;
    const int32_t sx = (f.x - FloorDiv(f.x, cell0_) * cell0_) / fine, sy = (f.y - FloorDiv(f.y, cell0_) * cell0_) / fine;
    const Posting posting{(slot << 8) | static_cast<uint32_t>(sx * side + sy)};
    // Lists stay sorted by slot (Retrieve reads them block by block): a
    // reused slot goes after the postings of smaller slots.
    auto& list = it->second;
    if (list.empty() || list.back().slot() <= slot) {
      list.push_back(posting);
    } else {
      list.insert(std::upper_bound(list.begin(), list.end(), posting,
                                   [](const Posting& a, const Posting& b) { return a.slot() < b.slot(); }),
                  posting);
    }
  }
  posting_count_ += features.size();
  slot_id_[slot] = id;
  slot_used_[slot] = 1;
  slot_features_[slot] = std::move(features);
  id_to_slot_[id] = slot;
  return Status::Ok();
}

bool Index::Remove(uint64_t id) {
  auto found = id_to_slot_.find(id);
  if (found == id_to_slot_.end()) return false;
  const uint32_t slot = found->second;
  std::vector<PoseFeature>& features = slot_features_[slot];
  for (size_t i = 0; i < features.size(); ++i) {
    const PoseFeature& f = features[i];
    const uint64_t key = PostingKey(f.word, FloorDiv(f.x, cell0_), FloorDiv(f.y, cell0_));
    if (i > 0 && key == PostingKey(features[i - 1].word, FloorDiv(features[i - 1].x, cell0_),
                                   FloorDiv(features[i - 1].y, cell0_)))
      continue;  // this list was already cleaned
    auto it = lists_.find(key);
    if (it == lists_.end()) continue;
    auto& list = it->second;
    list.erase(std::remove_if(list.begin(), list.end(), [slot](const Posting& p) { return p.slot() == slot; }),
               list.end());
    if (list.empty()) {
      lists_.erase(it);
      auto& word_lists = word_lists_[f.word];
      word_lists.erase(std::find_if(word_lists.begin(), word_lists.end(),
                                    [key](const WordList& l) { return l.key == key; }));
      if (word_lists.empty()) word_lists_.erase(f.word);
    }
  }
  for (const PoseFeature& f : features) {
    auto w = word_postings_.find(f.word);
    if (--w->second == 0) word_postings_.erase(w);
  }
  posting_count_ -= features.size();
  features = std::vector<PoseFeature>();
  slot_used_[slot] = 0;
  free_slots_.push_back(slot);
  id_to_slot_.erase(found);
  return true;
}

std::vector<uint32_t> Index::StopWords(double max_share) const {
  std::vector<uint32_t> stop;
  if (max_share >= 1.0) return stop;
  const double limit = max_share * static_cast<double>(posting_count_);
  for (const auto& kv : word_postings_)
    if (static_cast<double>(kv.second) > limit) stop.push_back(kv.first);
  std::sort(stop.begin(), stop.end());
  return stop;
}

size_t Index::CountPostingsOfMap(uint64_t id) const {
  auto found = id_to_slot_.find(id);
  if (found == id_to_slot_.end()) {
    return 0;
  }
  size_t n = 0;
  for (const auto& kv : lists_)
    for (const Posting& p : kv.second) n += p.slot() == found->second;
  return n;
}

size_t Index::MemoryBytes() const {
  constexpr size_t kNode = 48;  // rough per-entry cost of an unordered_map node + bucket
  size_t bytes = 0;
  for (const auto& kv : lists_) bytes += kNode + sizeof(kv.second) + kv.second.capacity() * sizeof(Posting);
  for (const auto& kv : word_lists_) bytes += kNode + sizeof(kv.second) + kv.second.capacity() * sizeof(WordList);
  bytes += word_postings_.size() * kNode;
  for (const auto& f : slot_features_) bytes += sizeof(f) + f.capacity() * sizeof(PoseFeature);
  bytes += id_to_slot_.size() * kNode + slot_id_.capacity() * (sizeof(uint64_t) + 1);
  return bytes;
}

void Index::ForEachMap(const std::function<void(uint64_t, const std::vector<PoseFeature>&)>& fn) const {
  for (size_t s = 0; s < slot_id_.size(); ++s)
    if (slot_used_[s]) fn(slot_id_[s], slot_features_[s]);
}

Result<std::vector<MapHit>> Index::Retrieve(const Lmd& query, const RetrieveOptions& options,
                                            RetrieveStats* stats) const {
  RetrieveStats local;
  if (stats == nullptr) stats = &local;
  *stats = RetrieveStats();
  Status st = ValidateRetrieveOptions(options);
  if (!st.ok()) return st;
  auto features = ToPoseFeatures(query, options_);
  if (!features.ok()) return features.status();
  const PreparedLmdQuery q =
      PrepareLmdQuery(WithoutStopWords(std::move(features).value(), StopWords(options.max_word_share)), options_, options);
  if (options.method == Method::kBow) return RetrieveBow(q, options.top_k, stats);
  return RetrieveLmd(q, options, stats);
}

std::vector<MapHit> Index::RetrieveLmd(const PreparedLmdQuery& q, const RetrieveOptions& options,
                                       RetrieveStats* stats) const {
  RetrieveScratch& sc = Scratch();
  if (sc.bounds.size() < slot_id_.size() * 4) sc.bounds.resize(slot_id_.size() * 4, 0);
  sc.touched.clear();
  uint32_t* bounds = sc.bounds.data();
  const int32_t box = q.max_offset;
  const int levels = q.levels;
  const size_t nq = q.features.size();
  // gain[l] = 2^L * (w_0 + ... + w_l): what a query feature adds to 2^L * raw K
  // when a same-word db feature lies in a level-l cell meeting its box
  // (cells nest, so every coarser level is met too).
  uint32_t gain[9];
  for (int l = 0; l <= levels; ++l) gain[l] = (l == 0 ? 1u : gain[l - 1] + (1u << (l - 1)));
  // A term = (query feature, orientation) with its box in cells of every level.
  struct Term {
    int o;
    int32_t lo_x[9], hi_x[9], lo_y[9], hi_y[9];
  };
  std::vector<Term> terms;
  std::vector<const WordList*> lists;
  std::vector<const Term*> active;
  // One posting list to read, with what its postings add (see below).
  struct ListRead {
    const std::vector<Posting>* list;
    size_t cursor;         // next posting to read
    // Offset in tables: per finest cell, the gains per orientation, then the
    // same capped for a map with a single posting in the list (see 1b).
    uint32_t table;
    uint32_t query_count;  // query features with the list's word
    bool one_term_each;    // at most one active term per orientation
    // Otherwise, per active term: its orientation (term_o[terms + a]) and
    // where it gains what: with at most 64 finest cells, per level l >= 1
    // the finest cells where it meets level l as bits
    // (term_masks[(terms + a) * levels + l - 1]; cells nest, so the masks
    // shrink with l), else its gain per finest cell
    // (term_gains[(terms + a) * cells + sub]).
    uint32_t terms;
    uint32_t term_count;
  };
  std::vector<ListRead> reads;
  std::vector<uint32_t>& tables = sc.tables;
  std::vector<uint32_t>& term_gains = sc.term_gains;
  std::vector<uint64_t>& term_masks = sc.term_masks;
  std::vector<uint8_t>& term_o = sc.term_o;
  tables.clear(), term_gains.clear(), term_masks.clear(), term_o.clear();
  const int32_t side = 1 << levels, cells = side * side;
  // A map's run of postings in a list then gains, per term, gain[the highest
  // level whose mask meets the run's cells]: a few tests per term instead
  // of one look-up per posting and term.
  const bool use_masks = cells <= 64;
  // What the query features of the words pass 1 skips could add to 2^L * raw
  // K, per orientation (RetrieveOptions::bound_skip_postings_per_map).
  const double skip_above = options.bound_skip_postings_per_map * static_cast<double>(size());
  uint32_t skipped_gain = 0;
  // Pass 1, per distinct query word: read each posting list that can matter
  // once; per map, add what its run of postings in the list can contribute
  // to 2^L * raw K per orientation (see the caps in 1b). A query feature
  // counts in K through the one level-0 cell its shifted position falls in,
  // so the sum over lists bounds K even where a term's box spans several cells.
  // 1a: the lists to read and their gain tables.
  for (size_t i = 0; i < nq;) {
    const uint32_t word = q.features[i].word;
    size_t e = i + 1;
    while (e < nq && q.features[e].word == word) ++e;
    const uint32_t query_count = static_cast<uint32_t>(e - i);
    const auto word_lists = word_lists_.find(word);
    if (word_lists == word_lists_.end()) {
      i = e;
      continue;
    }
    if (skip_above > 0 && static_cast<double>(word_postings_.at(word)) > skip_above) {
      skipped_gain += gain[levels] * query_count;
      i = e;
      continue;
    }
    terms.clear();
    for (int o = 0; o < 4; ++o) {
      for (size_t k = i; k < e; ++k) {
        Term t;
        t.o = o;
        const int32_t x = q.rx[o][k], y = q.ry[o][k];
        for (int l = 0; l <= levels; ++l) {
          const int32_t cw = q.cell0 >> l;
          t.lo_x[l] = FloorDiv(x - box, cw);
          t.hi_x[l] = FloorDiv(x + box, cw);
          t.lo_y[l] = FloorDiv(y - box, cw);
          t.hi_y[l] = FloorDiv(y + box, cw);
        }
        terms.push_back(t);
      }
    }
    i = e;
    // The word's lists whose level-0 cell meets a term's box, in key order.
    lists.clear();
    for (const WordList& word_list : word_lists->second) {
      const int32_t cx = CellX(word_list.key), cy = CellY(word_list.key);
      for (const Term& t : terms) {
        if (cx >= t.lo_x[0] && cx <= t.hi_x[0] && cy >= t.lo_y[0] && cy <= t.hi_y[0]) {
          lists.push_back(&word_list);
          break;
        }
      }
    }
    std::sort(lists.begin(), lists.end(), [](const WordList* a, const WordList* b) { return a->key < b->key; });
    for (const WordList* word_list : lists) {
      const std::vector<Posting>& postings = *word_list->postings;
      const int32_t cx = CellX(word_list->key), cy = CellY(word_list->key);
      active.clear();
      for (const Term& t : terms)
        if (cx >= t.lo_x[0] && cx <= t.hi_x[0] && cy >= t.lo_y[0] && cy <= t.hi_y[0]) active.push_back(&t);
      // The cell splits into side x side finest cells; per finest cell: the
      // gains of the active terms summed per orientation (table[sub * 4 + o]).
      ListRead read{&postings, 0, static_cast<uint32_t>(tables.size()), query_count, true,
                    static_cast<uint32_t>(term_o.size()), 0};
      int terms_per_orientation[4] = {0, 0, 0, 0};
      for (const Term* t : active) read.one_term_each &= ++terms_per_orientation[t->o] <= 1;
      if (!read.one_term_each) {
        read.term_count = static_cast<uint32_t>(active.size());
        if (use_masks) {
          term_masks.resize(term_masks.size() + active.size() * static_cast<size_t>(levels), 0);
        } else {
          term_gains.resize(term_gains.size() + active.size() * static_cast<size_t>(cells));
        }
      }
      tables.resize(tables.size() + static_cast<size_t>(cells) * 8, 0);
      uint32_t* table = tables.data() + read.table;
      for (size_t a = 0; a < active.size(); ++a) {
        const Term& t = *active[a];
        for (int32_t sx = 0; sx < side; ++sx) {
          for (int32_t sy = 0; sy < side; ++sy) {
            int met = 0;
            for (int l = 1; l <= levels; ++l) {
              const int32_t px = (cx * side + sx) >> (levels - l), py = (cy * side + sy) >> (levels - l);
              if (px < t.lo_x[l] || px > t.hi_x[l] || py < t.lo_y[l] || py > t.hi_y[l]) break;
              met = l;
            }
            const int32_t sub = sx * side + sy;
            table[static_cast<size_t>(sub) * 4 + static_cast<size_t>(t.o)] += gain[met];
            if (read.one_term_each) continue;
            if (!use_masks) {
              term_gains[(read.terms + a) * static_cast<size_t>(cells) + sub] = gain[met];
              continue;
            }
            for (int l = 1; l <= met; ++l)
              term_masks[(read.terms + a) * static_cast<size_t>(levels) + static_cast<size_t>(l - 1)] |= uint64_t{1} << sub;
          }
        }
        if (!read.one_term_each) term_o.push_back(static_cast<uint8_t>(t.o));
      }
      for (int32_t k = 0; k < cells * 4; ++k) table[cells * 4 + k] = std::min(table[k], gain[levels]);
      ++stats->lists_read;
      stats->postings_read += postings.size();
      reads.push_back(read);
    }
  }
  // 1b: the postings, one block of slots at a time, so that the per-map
  // accumulators of a block stay in cache while every list is read (lists are
  // sorted by slot; a list spans all maps, so reading lists one after the
  // other would fetch a map's accumulator from memory for nearly every posting).
  constexpr uint32_t kBlockSlots = 4096;
  for (uint32_t block_end = kBlockSlots;; block_end += kBlockSlots) {
    for (ListRead& read : reads) {
      const std::vector<Posting>& list = *read.list;
      const uint32_t* table = tables.data() + read.table;
      const uint32_t* single = table + static_cast<size_t>(cells) * 4;
      size_t r = read.cursor;
      while (r < list.size() && list[r].slot() < block_end) {
        const uint32_t slot = list[r].slot();
        uint32_t* b = bounds + 4 * static_cast<size_t>(slot);
        if ((b[0] | b[1] | b[2] | b[3]) == 0) sc.touched.push_back(slot);  // a read list always adds
        if (r + 1 == list.size() || list[r + 1].slot() != slot) {  // the common case: one posting
          const uint32_t* g = single + static_cast<size_t>(list[r].sub()) * 4;
          b[0] += g[0], b[1] += g[1], b[2] += g[2], b[3] += g[3];
          ++r;
          continue;
        }
        // Several postings (a map's postings are adjacent): each term gains
        // its best over the postings, capped by gain[L] per matchable pair
        // (min(query features, postings)) since I^l of one cell is at most that.
        size_t re = r + 1;
        while (re < list.size() && list[re].slot() == slot) ++re;
        uint32_t sum[4] = {0, 0, 0, 0};
        if (read.one_term_each) {
          for (size_t k = r; k < re; ++k) {
            const uint32_t* g = &table[static_cast<size_t>(list[k].sub()) * 4];
            for (int o = 0; o < 4; ++o) sum[o] = std::max(sum[o], g[o]);
          }
        } else if (use_masks) {
          uint64_t run = 0;
          for (size_t k = r; k < re; ++k) run |= uint64_t{1} << list[k].sub();
          for (uint32_t a = 0; a < read.term_count; ++a) {
            const uint64_t* masks = &term_masks[(read.terms + a) * static_cast<size_t>(levels)];
            int met = levels;
            while (met > 0 && (run & masks[met - 1]) == 0) --met;
            sum[term_o[read.terms + a]] += gain[met];
          }
        } else {
          for (uint32_t a = 0; a < read.term_count; ++a) {
            const uint32_t* g = &term_gains[(read.terms + a) * static_cast<size_t>(cells)];
            uint32_t best = 0;
            for (size_t k = r; k < re; ++k) best = std::max(best, g[list[k].sub()]);
            sum[term_o[read.terms + a]] += best;
          }
        }
        const uint32_t pairs = std::min(read.query_count, static_cast<uint32_t>(re - r));
        for (int o = 0; o < 4; ++o) b[o] += std::min(sum[o], gain[levels] * pairs);
        r = re;
      }
      read.cursor = r;
    }
    if (block_end >= slot_id_.size()) break;
  }
  if (skipped_gain > 0 && sc.touched.size() < options.top_k) {
    // The other words reach too few maps to fill the top k (a small store, or
    // maps made of common words only): read every list after all.
    for (uint32_t slot : sc.touched) std::fill_n(bounds + 4 * static_cast<size_t>(slot), 4, 0u);
    RetrieveOptions every_list = options;
    every_list.bound_skip_postings_per_map = 0.0;
    return RetrieveLmd(q, every_list, stats);
  }
  // Upper bound of each touched map's score (see index.h).
  struct Candidate {
    double bound;
    uint64_t id;
    uint32_t slot;
  };
  std::vector<Candidate> heap;
  heap.reserve(sc.touched.size());
  const double inv_scale = std::ldexp(1.0, -levels);
  auto bound_of = [&](uint32_t raw_scaled, size_t nd) {
    const double raw = std::min(static_cast<double>(raw_scaled) * inv_scale, static_cast<double>(std::min(nq, nd)));
    return NormalizeScore(raw, nq, nd, q.normalization);
  };
  for (uint32_t slot : sc.touched) {
    const uint32_t* c = bounds + 4 * static_cast<size_t>(slot);
    const uint32_t best = std::max(std::max(c[0], c[1]), std::max(c[2], c[3]));
    heap.push_back({bound_of(best + skipped_gain, slot_features_[slot].size()), slot_id_[slot], slot});
  }
  auto lower = [](const Candidate& a, const Candidate& b) {
    if (a.bound != b.bound) return a.bound < b.bound;
    return a.id > b.id;
  };
  stats->maps_touched = heap.size();
  std::make_heap(heap.begin(), heap.end(), lower);
  // Pass 2: exact scores, best bound first, until no bound can reach the top k.
  TopHits top(options.top_k);
  while (!heap.empty()) {
    const Candidate next = heap.front();
    if (top.full() && next.bound < top.kth_score()) break;
    if (options.max_maps_scored != 0 && top.full() && stats->maps_scored >= options.max_maps_scored) break;
    std::pop_heap(heap.begin(), heap.end(), lower);
    heap.pop_back();
    ++stats->maps_scored;
    const auto& db = slot_features_[next.slot];
    // Orientations whose own bound is below the k-th score cannot put the map
    // in the top k (nor be its best orientation there): not scored.
    unsigned orientations = 0xF;
    if (top.full()) {
      const uint32_t* c = bounds + 4 * static_cast<size_t>(next.slot);
      for (int o = 0; o < 4; ++o)
        if (bound_of(c[o] + skipped_gain, db.size()) < top.kth_score()) orientations &= ~(1u << o);
    }
    const KernelScore s = ScoreLmdMap(q, db.data(), db.size(), &sc.kernel, orientations);
    MapHit hit;
    hit.map_id = next.id;
    hit.score = s.score;
    hit.orientation = s.orientation;
    hit.offset = {s.offset_x * options_.pose_quantum_m, s.offset_y * options_.pose_quantum_m};
    top.Offer(hit);
  }
  for (uint32_t slot : sc.touched) std::fill_n(bounds + 4 * static_cast<size_t>(slot), 4, 0u);
  return top.Take();
}

std::vector<MapHit> Index::RetrieveBow(const PreparedLmdQuery& q, size_t top_k, RetrieveStats* stats) const {
  RetrieveScratch& sc = Scratch();
  if (sc.counts.size() < slot_id_.size()) sc.counts.resize(slot_id_.size(), 0);
  if (sc.word_counts.size() < slot_id_.size()) sc.word_counts.resize(slot_id_.size(), 0);
  sc.touched.clear();
  uint32_t* total = sc.counts.data();
  uint32_t* word_count = sc.word_counts.data();
  const size_t nq = q.features.size();
  for (size_t i = 0; i < nq;) {
    const uint32_t word = q.features[i].word;
    size_t e = i + 1;
    while (e < nq && q.features[e].word == word) ++e;
    const uint32_t query_count = static_cast<uint32_t>(e - i);
    i = e;
    auto word_lists = word_lists_.find(word);
    if (word_lists == word_lists_.end()) continue;
    sc.word_touched.clear();
    for (const WordList& word_list : word_lists->second) {
      const auto& list = *word_list.postings;
      ++stats->lists_read;
      stats->postings_read += list.size();
      for (const Posting& p : list) {
        if (word_count[p.slot()]++ == 0) sc.word_touched.push_back(p.slot());
      }
    }
    for (uint32_t slot : sc.word_touched) {
      if (total[slot] == 0) sc.touched.push_back(slot);
      total[slot] += std::min(query_count, word_count[slot]);
      word_count[slot] = 0;
    }
  }
  stats->maps_touched = stats->maps_scored = sc.touched.size();
  TopHits top(top_k);
  for (uint32_t slot : sc.touched) {
    MapHit hit;
    hit.map_id = slot_id_[slot];
    hit.score = NormalizeScore(static_cast<double>(total[slot]), nq, slot_features_[slot].size(), q.normalization);
    total[slot] = 0;
    top.Offer(hit);
  }
  return top.Take();
}

}  // namespace lmd

#include "core/index/retrieve_options.h"

#include <cmath>
#include <string>

namespace lmd {

Status ValidateIndexOptions(const IndexOptions& o) {
  if (!(o.pose_quantum_m > 0.0) || !std::isfinite(o.pose_quantum_m))
    return Status::InvalidArgument("pose_quantum_m must be > 0");
  if (o.pyramid_levels < 0 || o.pyramid_levels > 4)
    return Status::InvalidArgument("pyramid_levels must be in [0, 4]");
  if (!(o.pyramid_cell_m > 0.0) || !std::isfinite(o.pyramid_cell_m))
    return Status::InvalidArgument("pyramid_cell_m must be > 0");
  const double units = o.pyramid_cell_m / o.pose_quantum_m;
  const double rounded = std::round(units);
  if (std::fabs(units - rounded) > 1e-6 || rounded < 1 || rounded > 30000)
    return Status::InvalidArgument("pyramid_cell_m must be a whole number (1..30000) of pose_quantum_m");
  const long cell = static_cast<long>(rounded);
  if (cell % (1L << o.pyramid_levels) != 0)
    return Status::InvalidArgument("pyramid_cell_m / pose_quantum_m must be divisible by 2^pyramid_levels");
  return Status::Ok();
}

Status ValidateRetrieveOptions(const RetrieveOptions& o) {
  if (o.top_k < 1) return Status::InvalidArgument("top_k must be >= 1");
  if (!(o.max_offset_m >= 0.0) || !(o.max_offset_m <= 100.0))
    return Status::InvalidArgument("max_offset_m must be in [0, 100]");
  if (!(o.offset_bin_m > 0.0) || !(o.offset_bin_m <= 100.0))
    return Status::InvalidArgument("offset_bin_m must be in (0, 100]");
  if (!(o.max_word_share > 0.0) || !(o.max_word_share <= 1.0))
    return Status::InvalidArgument("max_word_share must be in (0, 1]");
  if (!(o.bound_skip_postings_per_map >= 0.0) || !std::isfinite(o.bound_skip_postings_per_map))
    return Status::InvalidArgument("bound_skip_postings_per_map must be >= 0");
  if (o.method != Method::kLmd && o.method != Method::kBow)
    return Status::InvalidArgument("unknown method");
  if (o.normalization != Normalization::kNone && o.normalization != Normalization::kMin &&
      o.normalization != Normalization::kSqrt)
    return Status::InvalidArgument("unknown normalization");
  return Status::Ok();
}

}  // namespace lmd

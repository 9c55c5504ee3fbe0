// Writer for CARMEN laser logs (what ReadCarmenLog reads back).
#pragma once

#include <ostream>
#include <string>

#include "core/io/laser_log.h"
#include "core/status.h"

namespace lmd {

// Writes one line per scan: FLASER when the scan spans 180 deg in the FLASER
// convention of carmen_reader.h (n even and centred beams, or n odd with end
// points), ROBOTLASER1 (which carries start angle, resolution and max range)
// otherwise. "No return" readings are written as the scan's max_range.
// FLASER lines carry no max range: a reader caps them with its own
// max_usable_range (30 m by default). Ranges are written with 1 mm precision,
// poses with 1e-6. A path ending in ".gz" is gzip-compressed. Returns IoError
// if the file cannot be written.
Status WriteCarmenLog(const std::string& path, const LaserLog& log);

// Same to a stream (plain text).
Status WriteCarmenLog(std::ostream& out, const LaserLog& log);

}  // namespace lmd

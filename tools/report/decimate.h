// Min/max-preserving decimation of a polyline for drawing (M4 aggregation).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace kuavo::report {

// Which of the n points (pixel coordinates, all finite) to draw: each maximal run of consecutive
// points inside one pixel column collapses to its first, lowest, highest and last point, kept in
// their original order. The drawn line then differs from the full one by less than a pixel, keeps
// every column's extremes (a one-sample spike still reaches its pixel) and a time series has at
// most 4 points per column. Paths that are not monotonic in x (a CoM trace) work the same way.
// keep is overwritten with ascending indices.
void decimate_min_max(std::span<const double> px, std::span<const double> py, std::vector<std::size_t>* keep);

}  // namespace kuavo::report

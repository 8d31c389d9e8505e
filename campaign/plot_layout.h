// Where things go on a figure's axes: curves cut at the window, log-axis labels that keep
// apart. Pure geometry, so it is tested without drawing (figures.cc draws with it).
#pragma once

#include <vector>

namespace jointlab::campaign {

/// The polyline (x, y) cut to lo <= x <= hi: a segment that crosses an end stops there, at
/// its linearly interpolated y, so that a curve neither runs past the frame nor stretches
/// the y range with points outside the window.
void clip_x(std::vector<double>& x, std::vector<double>& y, double lo, double hi);

/// Values of the labels of a log10 axis over [lo, hi] (log10 units): 1, 2, 5 x 10^k under two
/// decades (1 to 9 x 10^k under 0.8), decades above; a label closer than `min_gap` (a fraction
/// of the axis) to the one below it is left out, so that no two labels overlap.
std::vector<double> log_label_values(double lo, double hi, double min_gap);

}  // namespace jointlab::campaign

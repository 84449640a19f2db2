// mvtm — order statistics of samples (robust fits use them throughout).
//
// Both take the samples by value (they are partially reordered) and are O(n).
#pragma once

#include <vector>

namespace mvtm {

// The upper median: the element at index n/2 of the sorted samples; NaN when there are none.
double Median(std::vector<double> v);

// The middle median: the mean of the two middle samples when n is even; NaN when none.
double MiddleMedian(std::vector<double> v);

// The element at index round(q·(n−1)) of the sorted samples, q in [0, 1]; NaN when none.
double Percentile(std::vector<double> v, double q);

}  // namespace mvtm

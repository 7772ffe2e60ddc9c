#pragma once
/// Order statistics of samples.

#include <vector>

namespace csgvox {

/// The median of `values`: the value of rank n/2 in increasing order (for an
/// even count, the upper of the two middle values, so the result is always one
/// of the samples). NaN for no values. Linear time.
double median(std::vector<double> values);

}  // namespace csgvox

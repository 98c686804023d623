// The median the benchmark programs report: of an odd count the middle value, of an even
// count the mean of the middle two (as bench/run's own median()).
#pragma once

#include <algorithm>
#include <vector>

namespace tessera::bench {

inline double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : (values[n / 2 - 1] + values[n / 2]) / 2.0;
}

}  // namespace tessera::bench

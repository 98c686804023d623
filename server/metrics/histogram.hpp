// A Prometheus histogram: counts of observations at or under fixed bounds, their sum and
// their number, kept with atomics so that observing takes no lock.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace tessera {

class Histogram {
 public:
  // `bounds`: the buckets' upper bounds, increasing; +Inf is added.
  explicit Histogram(std::vector<double> bounds);
  void observe(double value);
  // NAME_bucket{LABELS,le="..."} lines (cumulative), then NAME_sum and NAME_count, in the
  // text exposition format. `labels` is "" or `key="value",...` without braces.
  void write(std::string& out, std::string_view name, std::string_view labels = "") const;
  std::uint64_t count() const { return count_.load(std::memory_order_relaxed); }

 private:
  std::vector<double> bounds_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> counts_;  // per bucket, not cumulative; +Inf last
  std::atomic<std::uint64_t> count_{0};
  std::atomic<double> sum_{0};
};

// A number as the exposition format writes it: integers without a fraction, +Inf.
std::string metric_number(double value);

}  // namespace tessera

// The positions (in hand-out order) of a job's pending tiles, as one bit each. Claims take
// the first ones, so a cursor skips the handed-out prefix: a job of a million tiles costs
// 128 KiB here, not the 40 MiB of a std::set<int>, and finding the next tile is a word scan.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace tessera {

class PendingTiles {
 public:
  // Room for positions 0 to `positions` - 1, none pending.
  void reset(std::size_t positions);
  // Adding a position already pending, or removing one that is not, changes nothing.
  void insert(int position);
  void erase(int position);
  bool contains(int position) const;
  std::size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  // The first pending position at or after `position`; -1 when there is none.
  int first_from(int position) const;

 private:
  std::vector<std::uint64_t> words_;
  std::size_t count_ = 0;
  // No pending position lies in a word before this one; moved on lazily by first_from().
  mutable std::size_t first_word_ = 0;
};

}  // namespace tessera

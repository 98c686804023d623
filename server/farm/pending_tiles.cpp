#include "server/farm/pending_tiles.hpp"

#include <algorithm>
#include <bit>

namespace tessera {

void PendingTiles::reset(std::size_t positions) {
  words_.assign((positions + 63) / 64, 0);
  count_ = 0;
  first_word_ = words_.size();
}

void PendingTiles::insert(int position) {
  const auto word = static_cast<std::size_t>(position) / 64;
  const std::uint64_t bit = std::uint64_t{1} << (position % 64);
  if (words_[word] & bit) return;
  words_[word] |= bit;
  ++count_;
  first_word_ = std::min(first_word_, word);
}

void PendingTiles::erase(int position) {
  const auto word = static_cast<std::size_t>(position) / 64;
  const std::uint64_t bit = std::uint64_t{1} << (position % 64);
  if (!(words_[word] & bit)) return;
  words_[word] &= ~bit;
  --count_;
}

bool PendingTiles::contains(int position) const {
  return (words_[static_cast<std::size_t>(position) / 64] >> (position % 64)) & 1;
}

int PendingTiles::first_from(int position) const {
  if (count_ == 0 || position < 0) return -1;
  auto word = static_cast<std::size_t>(position) / 64;
  std::uint64_t bits =
      word < words_.size() ? words_[word] & (~std::uint64_t{0} << (position % 64)) : 0;
  if (word < first_word_) {
    word = first_word_;
    bits = word < words_.size() ? words_[word] : 0;
  }
  const bool from_start = position == 0;
  while (bits == 0) {
    if (++word >= words_.size()) return -1;
    bits = words_[word];
  }
  if (from_start) first_word_ = word;  // everything before it was found empty
  return static_cast<int>(word * 64) + std::countr_zero(bits);
}

}  // namespace tessera

// "Did you mean" suggestions for misspelt keys, types and names in scene files.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string_view>

namespace tessera {

// Optimal-string-alignment distance: insertions, deletions, substitutions and swaps of
// two adjacent characters each cost 1, because swapped letters ("raduis") are the most
// common typo and plain Levenshtein would count them twice.
std::size_t edit_distance(std::string_view a, std::string_view b);

// The candidate closest to `word` (ignoring ASCII case), if one is close enough to be a
// plausible typo; ties go to the earlier candidate so that suggestions are stable.
std::optional<std::string_view> closest_match(std::string_view word,
                                              std::span<const std::string_view> candidates);

}  // namespace tessera

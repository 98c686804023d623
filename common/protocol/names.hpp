// The words an enum of the protocol is written as, looked up both ways. Each enum's table
// is its one spelling: on the wire, in the database and in docs/openapi.yaml's `enum`
// lists (the contract test compares them).
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "common/text/or_list.hpp"

namespace tessera::protocol {

template <typename E, std::size_t N>
using NameTable = std::array<std::pair<E, std::string_view>, N>;

template <typename E, std::size_t N>
constexpr std::string_view name_in(const NameTable<E, N>& table, E value) {
  for (const auto& [v, name] : table)
    if (v == value) return name;
  return "unknown";
}

template <typename E, std::size_t N>
constexpr std::optional<E> value_in(const NameTable<E, N>& table, std::string_view name) {
  for (const auto& [v, n] : table)
    if (n == name) return v;
  return std::nullopt;
}

// "a, b or c", for errors that list what is allowed.
template <typename E, std::size_t N>
std::string names_of(const NameTable<E, N>& table) {
  std::array<std::string_view, N> names;
  for (std::size_t i = 0; i < N; ++i) names[i] = table[i].second;
  return or_list(names);
}

}  // namespace tessera::protocol

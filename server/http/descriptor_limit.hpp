// How many connections a coordinator can take: its descriptors, less those its store, its
// image and asset files and its local workers need. Each connection is a descriptor, so a
// coordinator that let connections take them all would fail jobs for want of one to open
// a pixel file with.
#pragma once

#include <cstddef>
#include <cstdint>

namespace tessera {

struct DescriptorLimit {
  std::uint64_t was = 0;  // the soft limit the process started with
  std::uint64_t now = 0;  // after raising it to the hard limit
};

// Raises the soft limit of open descriptors to the hard limit (the most an unprivileged
// process may take), as the default soft limit of 1024 is far below what a farm's
// connections need.
DescriptorLimit raise_descriptor_limit();

struct ConnectionCaps {
  std::size_t total = 0;
  std::size_t per_peer = 0;
};

// The caps for a process of `descriptors`: a reserve of an eighth, at least 64, kept for
// everything but connections; a quarter of the rest for one peer address.
ConnectionCaps connection_caps(std::uint64_t descriptors);

}  // namespace tessera

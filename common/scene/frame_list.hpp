// Frame lists as render farms write them: "1-48", "1-100x2" (every second frame),
// "1,5,10-20", or a mix, each part a frame or a range with an optional step.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace tessera {

// A list that cannot be read, or names a frame the scene does not have; what() says what,
// and at which character (counted from 1).
class FrameListError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// The frames `text` names, ascending and each once, all within first..last; at most
// `max_count` of them.
std::vector<int> parse_frame_list(std::string_view text, int first, int last,
                                  std::size_t max_count);

// The shortest list parse_frame_list() reads back as `frames` (ascending, each once):
// runs of an even step written "a-bxs".
std::string format_frame_list(const std::vector<int>& frames);

}  // namespace tessera

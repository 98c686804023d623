#include "common/scene/frame_list.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdint>

#include "common/scene/animation.hpp"

namespace tessera {
namespace {

class ListReader {
 public:
  explicit ListReader(std::string_view text) : text_(text) {}

  bool done() const { return at_ == text_.size(); }
  bool accept(char c) {
    if (done() || text_[at_] != c) return false;
    ++at_;
    return true;
  }
  std::int64_t number(std::string_view what) {
    const std::size_t start = at_;
    while (!done() && std::isdigit(static_cast<unsigned char>(text_[at_])) != 0) ++at_;
    if (start == at_) fail_at(start, "expected " + std::string(what));
    std::int64_t value = 0;
    const auto [end, error] = std::from_chars(text_.data() + start, text_.data() + at_, value);
    if (error != std::errc() || value > max_frame_number)
      fail_at(start, "numbers are at most " + std::to_string(max_frame_number));
    return value;
  }
  std::size_t position() const { return at_; }
  [[noreturn]] void fail_at(std::size_t index, const std::string& detail) const {
    throw FrameListError("frame list \"" + std::string(text_) + "\", at character " +
                         std::to_string(index + 1) + ": " + detail);
  }

 private:
  std::string_view text_;
  std::size_t at_ = 0;
};

}  // namespace

std::vector<int> parse_frame_list(std::string_view text, int first, int last,
                                  std::size_t max_count) {
  ListReader reader(text);
  if (reader.done()) reader.fail_at(0, "expected a frame, a range a-b or a-bxstep");
  std::vector<int> frames;
  const auto check_frame = [&](std::int64_t frame, std::size_t where) {
    if (frame < first || frame > last) {
      reader.fail_at(where, "frame " + std::to_string(frame) + " is not one of the scene's, " +
                                std::to_string(first) + " to " + std::to_string(last));
    }
  };
  do {
    const std::size_t start = reader.position();
    const std::int64_t from = reader.number("a frame number");
    check_frame(from, start);
    std::int64_t to = from;
    std::int64_t step = 1;
    if (reader.accept('-')) {
      const std::size_t end_at = reader.position();
      to = reader.number("the range's last frame");
      check_frame(to, end_at);
      if (to < from)
        reader.fail_at(end_at, "a range must not end before it starts (" + std::to_string(from) +
                                   "-" + std::to_string(to) + ")");
      if (reader.accept('x')) {
        const std::size_t step_at = reader.position();
        step = reader.number("a step");
        if (step == 0) reader.fail_at(step_at, "the step must be at least 1");
      }
    }
    for (std::int64_t frame = from; frame <= to; frame += step) {
      if (frames.size() >= max_count) {
        reader.fail_at(
            start, "names more than " + std::to_string(max_count) + " frames (limit max_frames)");
      }
      frames.push_back(static_cast<int>(frame));
    }
  } while (reader.accept(','));
  if (!reader.done()) reader.fail_at(reader.position(), "expected \",\" or the end of the list");
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  return frames;
}

std::string format_frame_list(const std::vector<int>& frames) {
  std::string text;
  std::size_t i = 0;
  while (i < frames.size()) {
    if (!text.empty()) text += ',';
    text += std::to_string(frames[i]);
    // The longest run of one step from here; two frames are clearer as "a,b".
    std::size_t end = i + 1;
    if (end < frames.size()) {
      const int step = frames[end] - frames[i];
      while (end + 1 < frames.size() && frames[end + 1] - frames[end] == step) ++end;
      if (end - i >= 2) {
        text += '-' + std::to_string(frames[end]);
        if (step != 1) text += 'x' + std::to_string(step);
        i = end + 1;
        continue;
      }
    }
    ++i;
  }
  return text;
}

}  // namespace tessera

#include "common/net/event_stream.hpp"

#include <stdexcept>

namespace tessera {

bool EventStreamParser::feed(std::string_view piece) {
  partial_.append(piece);
  std::size_t start = 0;
  while (true) {
    const std::size_t end = partial_.find('\n', start);
    if (end == std::string::npos) break;
    std::string_view text(partial_.data() + start, end - start);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    start = end + 1;
    if (!line(text)) {
      partial_.erase(0, start);
      return false;
    }
  }
  partial_.erase(0, start);
  if (partial_.size() > kMaxLine)
    throw std::runtime_error("an event stream line longer than " + std::to_string(kMaxLine) +
                             " bytes");
  return true;
}

bool EventStreamParser::line(std::string_view text) {
  if (text.empty()) {  // the event's end
    if (!has_data_ && event_.type.empty()) return true;
    ServerEvent event = std::move(event_);
    if (event.type.empty()) event.type = "message";
    event_ = ServerEvent{};
    has_data_ = false;
    return on_event_(event);
  }
  if (text.front() == ':') return true;  // a comment
  const std::size_t colon = text.find(':');
  const std::string_view field = text.substr(0, colon);
  std::string_view value = colon == std::string_view::npos ? "" : text.substr(colon + 1);
  if (!value.empty() && value.front() == ' ') value.remove_prefix(1);
  if (field == "id") {
    event_.id = value;
  } else if (field == "event") {
    event_.type = value;
  } else if (field == "data") {
    if (has_data_) event_.data += '\n';
    event_.data += value;
    has_data_ = true;
  }
  return true;
}

}  // namespace tessera

// Server-sent events read from a stream of text in pieces of any size (the
// text/event-stream format): "id:", "event:" and "data:" lines, a blank line ending each
// event, and ":" comments (keep-alives) skipped.
#pragma once

#include <functional>
#include <string>
#include <string_view>

namespace tessera {

struct ServerEvent {
  std::string id;    // "" when the event had none
  std::string type;  // "message" when the event named none
  std::string data;  // its data lines, joined by "\n"
};

class EventStreamParser {
 public:
  // Called with each whole event; returns false to stop reading.
  using OnEvent = std::function<bool(const ServerEvent&)>;
  explicit EventStreamParser(OnEvent on_event) : on_event_(std::move(on_event)) {}

  // Takes the next piece; false once on_event has asked to stop.
  bool feed(std::string_view piece);
  // The longest line it holds while waiting for the line's end: a peer that sends one
  // endless line is refused (feed() throws std::runtime_error).
  static constexpr std::size_t kMaxLine = 64 << 20;

 private:
  bool line(std::string_view text);

  OnEvent on_event_;
  std::string partial_;
  ServerEvent event_;
  bool has_data_ = false;
};

}  // namespace tessera

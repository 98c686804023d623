// Text that many records hold alike: a lease's id in each of its tiles, a worker's in
// every tile it rendered. Each text is one allocation however many records hold it, and
// a record spends 8 bytes on it (a std::string spends 32, and copies the characters past
// 15). A job of millions of tiles is mostly these.
#pragma once

#include <atomic>
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>

#include <fmt/format.h>

namespace tessera {

class SharedText {
 public:
  SharedText() = default;
  // Implicit, as std::string's own: a record's field is assigned what a std::string took.
  SharedText(std::string_view text)
      : block_(text.empty() ? nullptr : new Block{{1}, std::string(text)}) {}
  SharedText(const std::string& text) : SharedText(std::string_view(text)) {}
  SharedText(const char* text) : SharedText(std::string_view(text)) {}
  SharedText(const SharedText& other) noexcept : block_(other.block_) {
    if (block_) block_->holders.fetch_add(1, std::memory_order_relaxed);
  }
  SharedText(SharedText&& other) noexcept : block_(std::exchange(other.block_, nullptr)) {}
  ~SharedText() { release(); }

  SharedText& operator=(const SharedText& other) noexcept {
    SharedText(other).swap(*this);
    return *this;
  }
  SharedText& operator=(SharedText&& other) noexcept {
    SharedText(std::move(other)).swap(*this);
    return *this;
  }
  // The same text again keeps the one held: no allocation.
  SharedText& operator=(std::string_view text) {
    if (view() != text) SharedText(text).swap(*this);
    return *this;
  }
  SharedText& operator=(const std::string& text) { return *this = std::string_view(text); }
  SharedText& operator=(const char* text) { return *this = std::string_view(text); }

  const std::string& str() const { return block_ ? block_->text : empty_text(); }
  operator const std::string&() const { return str(); }
  std::string_view view() const { return str(); }
  bool empty() const { return block_ == nullptr; }
  std::size_t size() const { return str().size(); }
  void clear() { SharedText().swap(*this); }
  void swap(SharedText& other) noexcept { std::swap(block_, other.block_); }

  friend bool operator==(const SharedText& a, const SharedText& b) {
    return a.block_ == b.block_ || a.view() == b.view();
  }
  friend bool operator==(const SharedText& a, const std::string& b) { return a.view() == b; }
  friend bool operator==(const SharedText& a, std::string_view b) { return a.view() == b; }
  friend bool operator==(const SharedText& a, const char* b) { return a.view() == b; }
  friend bool operator<(const SharedText& a, const SharedText& b) { return a.view() < b.view(); }
  friend std::string operator+(const std::string& a, const SharedText& b) { return a + b.str(); }
  friend std::string operator+(const char* a, const SharedText& b) { return a + b.str(); }
  friend std::string operator+(const SharedText& a, const std::string& b) { return a.str() + b; }
  friend std::string operator+(const SharedText& a, const char* b) { return a.str() + b; }

 private:
  struct Block {
    std::atomic<std::size_t> holders;
    std::string text;
  };
  static const std::string& empty_text() {
    static const std::string empty;
    return empty;
  }
  void release() noexcept {
    if (block_ && block_->holders.fetch_sub(1, std::memory_order_acq_rel) == 1) delete block_;
  }

  Block* block_ = nullptr;
};

}  // namespace tessera

template <>
struct fmt::formatter<tessera::SharedText> : fmt::formatter<std::string_view> {
  auto format(const tessera::SharedText& text, format_context& context) const {
    return fmt::formatter<std::string_view>::format(text.view(), context);
  }
};

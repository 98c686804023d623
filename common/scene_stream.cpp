#include "common/scene_stream.hpp"

#include <utility>

#include "common/scene_parser_parts.hpp"

namespace tessera {
namespace {

using nlohmann::json;

enum class Role : std::uint8_t { other, envelope, scene, objects, element };

struct Frame {
  json* value;  // the container being filled; stable while it is open (see place())
  Role role;
  std::string key;  // the last key read, in an object
};

// A DOM builder for nlohmann's SAX interface, as nlohmann's own, but for where the
// elements of the scene's "objects" go.
class ApartBuilder {
 public:
  ApartBuilder(std::optional<std::string_view> scene_member, ObjectTexts& objects)
      : scene_member_(scene_member), objects_(objects) {}

  json root;
  bool nested_too_deep = false;
  std::size_t error_position = 0;
  std::string error_what;

  bool null() { return scalar(json(nullptr)); }
  bool boolean(bool value) { return scalar(json(value)); }
  bool number_integer(json::number_integer_t value) { return scalar(json(value)); }
  bool number_unsigned(json::number_unsigned_t value) { return scalar(json(value)); }
  bool number_float(json::number_float_t value, const json::string_t&) {
    return scalar(json(value));
  }
  bool string(json::string_t& value) { return scalar(json(std::move(value))); }
  bool binary(json::binary_t& value) { return scalar(json(std::move(value))); }

  bool start_object(std::size_t) { return open(json::object(), false); }
  bool start_array(std::size_t) { return open(json::array(), true); }

  bool key(json::string_t& key) {
    stack_.back().key = std::move(key);
    return true;
  }

  bool end_object() { return close(); }
  bool end_array() { return close(); }

  bool parse_error(std::size_t position, const std::string&, const json::exception& error) {
    error_position = position;
    error_what = error.what();
    return false;
  }

 private:
  bool scalar(json&& value) {
    if (!stack_.empty() && stack_.back().role == Role::objects) {
      objects_.add(value);
      return true;
    }
    place(std::move(value));
    return true;
  }

  bool open(json&& container, bool array) {
    if (stack_.size() >= static_cast<std::size_t>(max_json_nesting)) {
      nested_too_deep = true;
      return false;
    }
    const Role role = role_of_child(array);
    json* where = nullptr;
    if (role == Role::element) {
      element_ = std::move(container);
      where = &element_;
    } else {
      where = place(std::move(container));
    }
    stack_.push_back(Frame{where, role, {}});
    return true;
  }

  bool close() {
    const Role role = stack_.back().role;
    stack_.pop_back();
    if (role == Role::element) {
      objects_.add(element_);
      element_ = json();
    }
    return true;
  }

  Role role_of_child(bool array) const {
    if (stack_.empty()) {
      if (array) return Role::other;
      return scene_member_ ? Role::envelope : Role::scene;
    }
    const Frame& parent = stack_.back();
    switch (parent.role) {
      case Role::envelope:
        return !array && parent.key == *scene_member_ ? Role::scene : Role::other;
      case Role::scene:
        return array && parent.key == "objects" ? Role::objects : Role::other;
      case Role::objects:
        return Role::element;
      default:
        return Role::other;
    }
  }

  // Puts a value where the parser is: the root, the next element of an array, or the
  // member of the last key (the last of repeated keys wins, as in nlohmann's parser).
  // Only the last element of an array is ever open, so pushing one moves no open one.
  json* place(json&& value) {
    if (stack_.empty()) {
      root = std::move(value);
      return &root;
    }
    Frame& parent = stack_.back();
    if (parent.value->is_array()) {
      json::array_t& array = parent.value->get_ref<json::array_t&>();
      array.push_back(std::move(value));
      return &array.back();
    }
    // A new "objects" (or a new scene) replaces the one before it, objects and all.
    if ((parent.role == Role::scene && parent.key == "objects") ||
        (parent.role == Role::envelope && parent.key == *scene_member_))
      objects_.clear();
    json& member = (*parent.value)[parent.key];
    member = std::move(value);
    return &member;
  }

  const std::optional<std::string_view> scene_member_;
  ObjectTexts& objects_;
  std::vector<Frame> stack_;
  json element_;  // the element of "objects" being read
};

}  // namespace

void ObjectTexts::clear() {
  text_.clear();
  ends_.clear();
}

void ObjectTexts::add(const json& element) {
  if (!ends_.empty()) text_ += ',';
  text_ += element.dump();
  ends_.push_back(text_.size());
}

std::string_view ObjectTexts::text(std::size_t index) const {
  const std::size_t begin = index == 0 ? 0 : ends_[index - 1] + 1;
  return std::string_view(text_).substr(begin, ends_[index] - begin);
}

json ObjectTexts::element(std::size_t index) const { return json::parse(text(index)); }

std::string ObjectTexts::take() && {
  ends_.clear();
  return std::move(text_);
}

json parse_json_objects_apart(std::string_view text, std::optional<std::string_view> scene_member,
                              ObjectTexts& objects) {
  objects.clear();
  ApartBuilder builder(scene_member, objects);
  if (json::sax_parse(text.begin(), text.end(), &builder)) return std::move(builder.root);
  if (builder.nested_too_deep) {
    check_nesting(text);
    throw SceneError("",
                     "JSON nesting is deeper than " + std::to_string(max_json_nesting) + " levels");
  }
  throw json_syntax_error(text, builder.error_position, builder.error_what);
}

std::string dump_scene(const json& document, ObjectTexts&& objects) {
  const auto found = document.is_object() ? document.find("objects") : document.end();
  if (found == document.end() || !found->is_array()) return document.dump();
  // dump() writes an object's members in the order of its std::map, "key":value with
  // commas and nothing else between them.
  std::string before = "{";
  std::string after = "]";
  bool past = false;
  for (auto it = document.begin(); it != document.end(); ++it) {
    std::string& out = past ? after : before;
    if (it != document.begin()) out += ',';
    out += json(it.key()).dump();
    out += ':';
    if (it == found) {
      before += '[';
      past = true;
    } else {
      out += it->dump();
    }
  }
  after += '}';
  std::string text = std::move(objects).take();
  text.insert(0, before);
  text += after;
  return text;
}

}  // namespace tessera

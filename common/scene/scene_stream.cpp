#include "common/scene/scene_stream.hpp"

#include <algorithm>
#include <map>
#include <span>
#include <utility>

#include "common/scene/scene_parser_parts.hpp"

namespace tessera {
namespace {

using nlohmann::json;

// The first three are role_in_envelope()'s.
enum class Role : std::uint8_t { other, envelope, scene, objects };

struct Frame {
  json* value;  // the container being filled; stable while it is open (see place())
  Role role;
  std::string key;  // the last key read, in an object
};

// nlohmann's dump() of a value, written as the parser reads it, without its nodes: an
// array's elements in order, an object's members (the last of repeated keys) in the order
// of its std::map, `"key":value` with commas and nothing else between them.
class CanonicalWriter {
 public:
  bool active() const { return !stack_.empty(); }
  std::size_t depth() const { return stack_.size(); }

  void open(bool array) {
    stack_.emplace_back();
    stack_.back().array = array;
    if (array) stack_.back().text = '[';
  }
  void key(std::string&& key) { stack_.back().key = std::move(key); }
  void scalar(const json& value) { put(value.dump()); }  // within an open value
  // The value's text when the one closed is the outermost, else nothing.
  std::optional<std::string> close() {
    Open done = std::move(stack_.back());
    stack_.pop_back();
    if (done.array) {
      done.text += ']';
      return put(std::move(done.text));
    }
    std::string text = "{";
    for (const auto& [key, value] : done.members) {
      if (text.size() > 1) text += ',';
      text += json(key).dump();
      text += ':';
      text += value;
    }
    text += '}';
    return put(std::move(text));
  }

 private:
  struct Open {
    bool array = false;
    std::string text;                            // an array's, so far
    std::map<std::string, std::string> members;  // an object's, each value's text
    std::string key;
  };

  std::optional<std::string> put(std::string&& text) {
    if (stack_.empty()) return std::move(text);
    Open& parent = stack_.back();
    if (parent.array) {
      if (parent.text.size() > 1) parent.text += ',';
      parent.text += text;
    } else {
      parent.members.insert_or_assign(std::move(parent.key), std::move(text));
    }
    return std::nullopt;
  }

  std::vector<Open> stack_;
};

// A DOM builder for nlohmann's SAX interface, as nlohmann's own, but for where the
// elements of the scene's "objects" go.
class ApartBuilder {
 public:
  ApartBuilder(std::optional<std::string_view> scene_member,
               std::span<const std::string_view> envelope_keys, ObjectTexts& objects)
      : scene_member_(scene_member), envelope_keys_(envelope_keys), objects_(objects) {}

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
    if (skipped_ > 0) return true;
    if (element_.active())
      element_.key(std::move(key));
    else
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
    if (skipped_ > 0) return true;
    if (element_.active()) {
      element_.scalar(value);
    } else if (unknown_member()) {
      place(json(nullptr));
    } else if (!stack_.empty() && stack_.back().role == Role::objects) {
      objects_.add_text(value.dump());
    } else {
      place(std::move(value));
    }
    return true;
  }

  bool open(json&& container, bool array) {
    if (stack_.size() + element_.depth() + skipped_ >= static_cast<std::size_t>(max_json_nesting)) {
      nested_too_deep = true;
      return false;
    }
    if (skipped_ > 0 || unknown_member()) {
      if (skipped_++ == 0) place(json(nullptr));
      return true;
    }
    // An element of "objects", and all within it, is written as text rather than built.
    if (element_.active() || (!stack_.empty() && stack_.back().role == Role::objects)) {
      element_.open(array);
      return true;
    }
    stack_.push_back(Frame{place(std::move(container)), role_of_child(array), {}});
    return true;
  }

  bool close() {
    if (skipped_ > 0) {
      --skipped_;
    } else if (!element_.active()) {
      stack_.pop_back();
    } else if (auto text = element_.close()) {
      objects_.add_text(*text);
    }
    return true;
  }

  // A member of the scene, or of the envelope, that their parsers refuse by its key alone:
  // its value is not built (null stands for it), so that junk costs nothing before the
  // refusal.
  bool unknown_member() const {
    if (stack_.empty()) return false;
    const Frame& parent = stack_.back();
    const auto known = [&](std::span<const std::string_view> keys) {
      return std::find(keys.begin(), keys.end(), parent.key) != keys.end();
    };
    if (parent.role == Role::scene) return !known(scene_keys);
    return parent.role == Role::envelope && !envelope_keys_.empty() && !known(envelope_keys_);
  }

  Role role_of_child(bool array) const {
    if (auto role = role_in_envelope<Role>(stack_, array, scene_member_)) return *role;
    const Frame& parent = stack_.back();
    switch (parent.role) {
      case Role::scene:
        return array && parent.key == "objects" ? Role::objects : Role::other;
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
  const std::span<const std::string_view> envelope_keys_;
  ObjectTexts& objects_;
  std::vector<Frame> stack_;
  CanonicalWriter element_;  // the element of "objects" being read, if any
  std::size_t skipped_ = 0;  // open containers of an unknown member's value
};

// An element of "objects" read back from its text for checking, as json::parse() would, but
// with a mesh's "positions", "normals" and "triangles" lifted out as LiftedTriples (as
// parse_json_fast_lifted() does): a mesh of a million triangles would be tens of millions
// of nodes. Gives up (refused) at anything those arrays cannot hold; the caller then parses
// the element the ordinary way, which words any error.
class LiftingReader {
 public:
  LiftingReader(const std::string& pointer, LiftedArrays& lifted)
      : pointer_(pointer), lifted_(lifted) {}

  json root;
  bool refused = false;

  bool null() { return scalar(json(nullptr)); }
  bool boolean(bool value) { return scalar(json(value)); }
  bool number_integer(json::number_integer_t value) {
    if (lifting_)
      return value >= 0 ? index(static_cast<std::uint64_t>(value), static_cast<double>(value))
                        : number(static_cast<double>(value));
    return scalar(json(value));
  }
  bool number_unsigned(json::number_unsigned_t value) {
    if (lifting_) return index(value, static_cast<double>(value));
    return scalar(json(value));
  }
  bool number_float(json::number_float_t value, const json::string_t&) {
    if (lifting_) return number(value);
    return scalar(json(value));
  }
  bool string(json::string_t& value) { return scalar(json(std::move(value))); }
  bool binary(json::binary_t& value) { return scalar(json(std::move(value))); }

  bool start_object(std::size_t) {
    if (lifting_) return refuse();
    stack_.push_back(place(json::object()));
    return true;
  }
  bool start_array(std::size_t) {
    if (lifting_) {
      if (in_triple_) return refuse();
      in_triple_ = true;
      in_triple_count_ = 0;
      return true;
    }
    // A member of the element itself, of the three a mesh's lifted arrays have.
    if (stack_.size() == 1 && root.is_object() &&
        (key_ == "positions" || key_ == "normals" || key_ == "triangles")) {
      lifting_ = true;
      indices_ = key_ == "triangles";
      triples_ = LiftedTriples{};
      return true;
    }
    stack_.push_back(place(json::array()));
    return true;
  }
  bool key(json::string_t& key) {
    key_ = std::move(key);
    return true;
  }
  bool end_object() {
    stack_.pop_back();
    return true;
  }
  bool end_array() {
    if (!lifting_) {
      stack_.pop_back();
      return true;
    }
    if (in_triple_) {
      if (in_triple_count_ != 3) return refuse();
      in_triple_ = false;
      return true;
    }
    lifting_ = false;
    lifted_.insert_or_assign(pointer_ + "/" + key_, std::move(triples_));
    place(json::array());  // stands for the lifted array, as in parse_json_fast_lifted()
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const json::exception&) { return refuse(); }

 private:
  bool refuse() {
    refused = true;
    return false;
  }

  bool scalar(json&& value) {
    if (lifting_) return refuse();
    place(std::move(value));
    return true;
  }

  // An index of "triangles", or a number of the others: as lift() reads them.
  bool index(std::uint64_t value, double as_number) {
    if (!indices_) return number(as_number);
    if (!in_triple_ || ++in_triple_count_ > 3) return refuse();
    triples_.indices.push_back(value);
    return true;
  }
  bool number(double value) {
    if (indices_ || !in_triple_ || ++in_triple_count_ > 3) return refuse();
    triples_.numbers.push_back(value);
    return true;
  }

  json* place(json&& value) {
    if (stack_.empty()) {
      root = std::move(value);
      return &root;
    }
    json& parent = *stack_.back();
    if (parent.is_array()) {
      json::array_t& array = parent.get_ref<json::array_t&>();
      array.push_back(std::move(value));
      return &array.back();
    }
    json& member = parent[key_];
    member = std::move(value);
    return &member;
  }

  const std::string& pointer_;
  LiftedArrays& lifted_;
  std::vector<json*> stack_;
  std::string key_;
  bool lifting_ = false;
  bool indices_ = false;
  bool in_triple_ = false;
  int in_triple_count_ = 0;
  LiftedTriples triples_;
};

}  // namespace

void ObjectTexts::clear() {
  text_.clear();
  ends_.clear();
}

void ObjectTexts::add_text(std::string_view element) {
  if (!ends_.empty()) text_ += ',';
  text_ += element;
  ends_.push_back(text_.size());
}

std::string_view ObjectTexts::text(std::size_t index) const {
  const std::size_t begin = index == 0 ? 0 : ends_[index - 1] + 1;
  return std::string_view(text_).substr(begin, ends_[index] - begin);
}

json ObjectTexts::element(std::size_t index) const { return json::parse(text(index)); }

std::optional<json> ObjectTexts::element_lifted(std::size_t index, const std::string& pointer,
                                                LiftedArrays& lifted) const {
  const std::string_view element = text(index);
  // A dump() writes keys in order, and "type" is the last a mesh may have.
  if (!element.ends_with(R"("type":"mesh"})")) return std::nullopt;
  lifted.clear();
  LiftingReader reader(pointer, lifted);
  if (!json::sax_parse(element.begin(), element.end(), &reader) || reader.refused) {
    lifted.clear();
    return std::nullopt;
  }
  return std::move(reader.root);
}

std::string ObjectTexts::take() && {
  ends_.clear();
  return std::move(text_);
}

json parse_json_objects_apart(std::string_view text, std::optional<std::string_view> scene_member,
                              ObjectTexts& objects,
                              std::span<const std::string_view> envelope_keys) {
  objects.clear();
  ApartBuilder builder(scene_member, envelope_keys, objects);
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

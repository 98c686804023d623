#include "common/scene/scene_limits_scan.hpp"

#include <cstddef>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/scene/scene_parser_parts.hpp"
#include "common/scene/value_reader.hpp"

namespace tessera {
namespace {

using nlohmann::json;

// What a container is to the scene; only these are counted. The first three are
// role_in_envelope()'s.
enum class Role : std::uint8_t {
  other,
  envelope,   // the root, when the scene is one of its members
  scene,      // the scene's own object
  materials,  // its "materials" object
  lights,     // its "lights" array
  objects,    // its "objects" array
  object,     // an element of "objects"
  triangles,  // an object's "triangles" array
};

struct Frame {
  Role role = Role::other;
  bool array = false;
  std::size_t elements = 0;  // of an array, so far
  std::string key;           // the last key read, where the role makes keys matter
  bool lifted = false;       // in a mesh's positions, normals or triangles
};

// The most JSON values one piece of a scene may hold outside a mesh's big arrays. A piece
// (a member of the scene or of "materials", an element of "objects" or "lights") is built
// as nodes whole when it is checked, at tens of bytes a value: this keeps that cost to a
// few MiB however the text is made. Valid pieces hold a few dozen values.
constexpr std::size_t kMaxPieceValues = 65536;

enum class ShapeKind : std::uint8_t { uncounted, box, triangle, mesh };

// The element of "objects" being read: as in the document, the last of repeated keys wins.
struct ObjectState {
  std::size_t index = 0;
  ShapeKind kind = ShapeKind::uncounted;
  bool inline_material = false;
  std::size_t triangles = 0;  // elements of its (last) "triangles" array
};

// nlohmann's SAX interface, statically dispatched. Refusals are thrown from the callbacks,
// which nlohmann's parser lets through: nothing after the first one is read.
class LimitCounter {
 public:
  LimitCounter(const Limits& limits, std::optional<std::string_view> scene_member)
      : limits_(limits), scene_member_(scene_member) {}

  bool nested_too_deep = false;
  std::size_t error_position = 0;
  std::string error_what;

  bool null() { return scalar(); }
  bool boolean(bool) { return scalar(); }
  bool number_integer(json::number_integer_t) { return scalar(); }
  bool number_unsigned(json::number_unsigned_t) { return scalar(); }
  bool number_float(json::number_float_t, const json::string_t&) { return scalar(); }
  bool binary(json::binary_t&) { return scalar(); }

  bool string(json::string_t& text) { return scalar(&text); }

  bool start_object(std::size_t) { return open(false); }
  bool start_array(std::size_t) { return open(true); }

  bool key(json::string_t& key) {
    Frame& frame = stack_.back();
    switch (frame.role) {
      case Role::envelope:
      case Role::scene:
      case Role::object:
        frame.key = key;
        break;
      case Role::materials:
        frame.key = key;
        add_named_material(key);
        break;
      default:
        break;
    }
    return true;
  }

  bool end_object() {
    if (stack_.back().role == Role::object) end_scene_object();
    close();
    return true;
  }

  bool end_array() {
    if (stack_.back().role == Role::triangles) object_.triangles = stack_.back().elements;
    close();
    return true;
  }

  bool parse_error(std::size_t position, const std::string&, const json::exception& error) {
    error_position = position;
    error_what = error.what();
    return false;
  }

 private:
  bool in(Role role) const { return !stack_.empty() && stack_.back().role == role; }

  // A value that is neither an object nor an array, as it begins; `text` if a string.
  bool scalar(const json::string_t* text = nullptr) {
    if (in(Role::object)) {
      const std::string& key = stack_.back().key;
      if (key == "type")
        object_.kind = text ? kind_named(*text) : ShapeKind::uncounted;
      else if (key == "material")
        object_.inline_material = false;
      else if (key == "triangles")
        object_.triangles = 0;
    }
    count_element();
    count_piece_value(!stack_.empty() && stack_.back().lifted);
    return true;
  }

  static ShapeKind kind_named(const std::string& type) {
    if (type == "box") return ShapeKind::box;
    if (type == "triangle") return ShapeKind::triangle;
    if (type == "mesh") return ShapeKind::mesh;
    return ShapeKind::uncounted;
  }

  bool open(bool array) {
    if (stack_.size() >= static_cast<std::size_t>(max_json_nesting)) {
      nested_too_deep = true;
      return false;
    }
    count_element();
    const Role role = role_of_child(array);
    const bool lifted = lifted_child(array);
    if (piece_depth_ == 0 && (role == Role::other || role == Role::object))
      if (auto pointer = piece_of_child()) {
        piece_depth_ = stack_.size() + 1;
        piece_values_ = 0;
        piece_pointer_ = std::move(*pointer);
      }
    count_piece_value(lifted);
    switch (role) {
      case Role::scene:
        named_.clear();
        start_objects();
        break;
      case Role::materials:
        named_.clear();
        break;
      case Role::objects:
        start_objects();
        break;
      case Role::object:
        object_ = ObjectState{stack_.back().elements - 1};
        break;
      default:
        break;
    }
    if (in(Role::object)) {
      const std::string& key = stack_.back().key;
      if (key == "type") object_.kind = ShapeKind::uncounted;
      if (key == "material") object_.inline_material = !array;  // an array: parse_scene says
      if (key == "triangles" && !array) object_.triangles = 0;
    }
    stack_.push_back(Frame{role, array, 0, {}, lifted});
    return true;
  }

  void close() {
    if (piece_depth_ == stack_.size()) piece_depth_ = 0;
    stack_.pop_back();
  }

  // A mesh's big arrays are read apart from the nodes (LiftedTriples), so not counted.
  bool lifted_child(bool array) const {
    if (stack_.empty()) return false;
    const Frame& parent = stack_.back();
    if (parent.lifted) return true;
    return array && parent.role == Role::object &&
           (parent.key == "positions" || parent.key == "normals" || parent.key == "triangles");
  }

  // The JSON Pointer of the piece a container opening here begins, if it begins one (the
  // counted containers, "objects", "lights" and "materials", are not pieces: their
  // elements are).
  std::optional<std::string> piece_of_child() const {
    if (stack_.empty()) return std::nullopt;
    const Frame& parent = stack_.back();
    switch (parent.role) {
      case Role::scene:
        return "/" + pointer_token(parent.key);
      case Role::materials:
        return "/materials/" + pointer_token(parent.key);
      case Role::objects:
        return "/objects/" + std::to_string(parent.elements - 1);
      case Role::lights:
        return "/lights/" + std::to_string(parent.elements - 1);
      default:
        return std::nullopt;
    }
  }

  void count_piece_value(bool lifted) {
    if (piece_depth_ == 0 || lifted || ++piece_values_ <= kMaxPieceValues) return;
    throw SceneError(piece_pointer_, "holds more than " + std::to_string(kMaxPieceValues) +
                                         " JSON values outside a mesh's positions, normals and "
                                         "triangles; a valid one holds a few dozen");
  }

  Role role_of_child(bool array) const {
    if (auto role = role_in_envelope<Role>(stack_, array, scene_member_)) return *role;
    const Frame& parent = stack_.back();
    switch (parent.role) {
      case Role::scene:
        if (!array && parent.key == "materials") return Role::materials;
        if (array && parent.key == "lights") return Role::lights;
        if (array && parent.key == "objects") return Role::objects;
        return Role::other;
      case Role::objects:
        return array ? Role::other : Role::object;
      case Role::object:
        return array && parent.key == "triangles" ? Role::triangles : Role::other;
      default:
        return Role::other;
    }
  }

  void start_objects() {
    triangles_ = 0;
    inline_materials_.clear();
  }

  // Every value, as it begins, is one more element of the array it is in, if any.
  void count_element() {
    if (stack_.empty() || !stack_.back().array) return;
    Frame& frame = stack_.back();
    const std::size_t index = frame.elements++;
    switch (frame.role) {
      case Role::objects:
        if (index >= limits_.max_objects)
          too_many("/objects", "elements", limits_.max_objects, "max_objects", index);
        break;
      case Role::lights:
        if (index >= limits_.max_lights)
          too_many("/lights", "elements", limits_.max_lights, "max_lights", index);
        break;
      case Role::triangles:
        // A huge mesh is refused within its own array, once its type is known to be "mesh".
        if (object_.kind == ShapeKind::mesh && triangles_ + index >= limits_.max_triangles)
          throw SceneError("/objects",
                           "must have <= " + std::to_string(limits_.max_triangles) +
                               " triangles in total (limit max_triangles), got more, counting up "
                               "to /objects/" +
                               std::to_string(object_.index),
                           "max_triangles", limits_.max_triangles);
        break;
      default:
        break;
    }
  }

  [[noreturn]] void too_many(const std::string& pointer, const char* what, std::size_t limit,
                             const char* name, std::size_t index) const {
    throw SceneError(pointer,
                     "must have <= " + std::to_string(limit) + " " + what + " (limit " + name +
                         "), got more (stopped counting at " + pointer + "/" +
                         std::to_string(index) + ")",
                     name, limit);
  }

  void add_named_material(const std::string& name) {
    // Repeated names are one material, as in the document.
    if (!named_.insert(name).second) return;
    if (named_.size() > limits_.max_materials)
      throw SceneError("/materials",
                       "must have <= " + std::to_string(limits_.max_materials) +
                           " entries (limit max_materials), got more (stopped counting at " +
                           quote(name) + ")",
                       "max_materials", limits_.max_materials);
    check_all_materials();
  }

  // Named materials come first in the table, then each object's inline one in order: the
  // one that goes over is the inline one at (limit - named).
  void check_all_materials() const {
    const std::size_t limit = limits_.max_materials;
    if (named_.size() + inline_materials_.size() <= limit) return;
    const std::size_t object = inline_materials_[limit - named_.size()];
    throw SceneError("/objects/" + std::to_string(object) + "/material",
                     "is one material too many: named and inline materials together must be <= " +
                         std::to_string(limit) + " (limit max_materials)",
                     "max_materials", limit);
  }

  // In parse_scene's order for one object: its material, then its triangles.
  void end_scene_object() {
    if (object_.inline_material) {
      inline_materials_.push_back(object_.index);
      check_all_materials();
    }
    switch (object_.kind) {
      case ShapeKind::box:
        triangles_ += 12;
        break;
      case ShapeKind::triangle:
        triangles_ += 1;
        break;
      case ShapeKind::mesh:
        triangles_ += object_.triangles;
        break;
      case ShapeKind::uncounted:
        break;
    }
    if (triangles_ > limits_.max_triangles)
      throw SceneError("/objects",
                       "must have <= " + std::to_string(limits_.max_triangles) +
                           " triangles in total (limit max_triangles), got " +
                           std::to_string(triangles_) + " counting up to /objects/" +
                           std::to_string(object_.index),
                       "max_triangles", limits_.max_triangles);
  }

  const Limits& limits_;
  const std::optional<std::string_view> scene_member_;
  std::vector<Frame> stack_;
  std::size_t piece_depth_ = 0;  // the size of stack_ with the piece's frame on top; 0: none
  std::size_t piece_values_ = 0;
  std::string piece_pointer_;
  ObjectState object_;
  std::unordered_set<std::string> named_;
  std::vector<std::size_t> inline_materials_;  // the objects that define one, in order
  std::size_t triangles_ = 0;
};

}  // namespace

void scan_scene_limits(std::string_view text, const Limits& limits,
                       std::optional<std::string_view> scene_member) {
  LimitCounter counter(limits, scene_member);
  if (json::sax_parse(text.begin(), text.end(), &counter)) return;
  if (counter.nested_too_deep) {
    check_nesting(text);  // words it as parse_json_text() does
    throw SceneError("",
                     "JSON nesting is deeper than " + std::to_string(max_json_nesting) + " levels");
  }
  throw json_syntax_error(text, counter.error_position, counter.error_what);
}

}  // namespace tessera

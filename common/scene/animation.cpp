#include "common/scene/animation.hpp"

#include <algorithm>

namespace tessera {
namespace {

using Value = std::array<double, 3>;

// Catmull-Rom on keys at uneven frames: the tangent at a key is the difference of its two
// neighbours over the frames between them, and an end key's missing neighbour is a copy of
// the end key one segment further out ("clamped"), which halves the one-sided slope there.
Value smooth_value(const std::vector<TrackKey>& keys, std::size_t i, int frame, int size) {
  const TrackKey& a = keys[i];
  const TrackKey& b = keys[i + 1];
  const double span = static_cast<double>(b.frame) - a.frame;
  const double s = (static_cast<double>(frame) - a.frame) / span;
  const double s2 = s * s;
  const double s3 = s2 * s;
  const double h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
  const double h10 = s3 - 2.0 * s2 + s;
  const double h01 = -2.0 * s3 + 3.0 * s2;
  const double h11 = s3 - s2;
  const bool has_before = i > 0;
  const bool has_after = i + 2 < keys.size();
  const double before_frame = has_before ? keys[i - 1].frame : a.frame - span;
  const double after_frame = has_after ? keys[i + 2].frame : b.frame + span;
  Value out{};
  for (int c = 0; c < size; ++c) {
    const double before = has_before ? keys[i - 1].value[c] : a.value[c];
    const double after = has_after ? keys[i + 2].value[c] : b.value[c];
    const double tangent_a = (b.value[c] - before) / (b.frame - before_frame);
    const double tangent_b = (after - a.value[c]) / (after_frame - a.frame);
    out[c] = h00 * a.value[c] + h10 * span * tangent_a + h01 * b.value[c] + h11 * span * tangent_b;
  }
  return out;
}

}  // namespace

std::array<double, 3> track_value(const Track& track, int frame) {
  const std::vector<TrackKey>& keys = track.keys;
  if (frame <= keys.front().frame) return keys.front().value;
  if (frame >= keys.back().frame) return keys.back().value;
  // The last key at or before the frame; there is one after it.
  const auto after = std::upper_bound(keys.begin(), keys.end(), frame,
                                      [](int f, const TrackKey& key) { return f < key.frame; });
  const std::size_t i = static_cast<std::size_t>(after - keys.begin()) - 1;
  const TrackKey& a = keys[i];
  const TrackKey& b = keys[i + 1];
  if (frame == a.frame || track.interpolation == Interpolation::step) return a.value;
  Value out{};
  if (track.interpolation == Interpolation::linear) {
    const double s =
        (static_cast<double>(frame) - a.frame) / (static_cast<double>(b.frame) - a.frame);
    for (int c = 0; c < track.size; ++c) out[c] = a.value[c] + s * (b.value[c] - a.value[c]);
    return out;
  }
  out = smooth_value(keys, i, frame, track.size);
  if (track.bounded) {
    for (int c = 0; c < track.size; ++c)
      out[c] =
          std::clamp(out[c], std::min(a.value[c], b.value[c]), std::max(a.value[c], b.value[c]));
  }
  return out;
}

bool Animation::changes(TrackTarget target) const {
  return std::any_of(tracks.begin(), tracks.end(),
                     [&](const Track& track) { return track.target == target; });
}

bool Animation::changes_objects() const {
  // A material that begins or ceases to let light through changes how its shapes are
  // registered: their geometry is built again, from the scene read whole.
  return std::any_of(tracks.begin(), tracks.end(), [](const Track& track) {
    return track.target == TrackTarget::object ||
           (track.target == TrackTarget::named_material &&
            std::string_view(track.pointer).ends_with("/transmission"));
  });
}

}  // namespace tessera

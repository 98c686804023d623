// Where each frame of an animation goes: a file name with runs of '#' standing for the
// frame number, zero-padded to the run's length ("out_####.png", frame 7: "out_0007.png").
#pragma once

#include <string>
#include <string_view>

namespace tessera {

bool has_frame_number(std::string_view pattern);
// Every run of '#' replaced by `frame`, padded with zeros to the run's length (a longer
// number is written whole).
std::string frame_path(std::string_view pattern, int frame);

}  // namespace tessera

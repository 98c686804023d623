// RAII around Embree's device and scene handles. Embree reports errors through a C
// callback; we record the message there and throw from C++ after the call returns,
// since an exception must not unwind through Embree's own frames.
#pragma once

#include <memory>
#include <string>

#include <embree3/rtcore.h>

#include "tracer/tracer_api.hpp"

namespace tessera {

class TESSERA_TRACER_API EmbreeDevice {
 public:
  EmbreeDevice();
  ~EmbreeDevice();
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;

  RTCDevice get() const { return device_; }

  // Throws std::runtime_error naming `what` if Embree reported an error since the last check.
  void check(const char* what) const;

 private:
  static void on_error(void* user, RTCError code, const char* message);

  RTCDevice device_ = nullptr;
  mutable std::string pending_error_;
};

class TESSERA_TRACER_API EmbreeScene {
 public:
  explicit EmbreeScene(const EmbreeDevice& device);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  RTCScene get() const { return scene_; }

 private:
  RTCScene scene_ = nullptr;
};

}  // namespace tessera

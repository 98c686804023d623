#include "tracer/embree_device.hpp"

#include <stdexcept>

namespace tessera {

EmbreeDevice::EmbreeDevice() {
  device_ = rtcNewDevice(nullptr);
  if (!device_)
    throw std::runtime_error("cannot create the Embree device (error " +
                             std::to_string(rtcGetDeviceError(nullptr)) + ")");
  rtcSetDeviceErrorFunction(device_, &EmbreeDevice::on_error, this);
}

EmbreeDevice::~EmbreeDevice() { rtcReleaseDevice(device_); }

void EmbreeDevice::on_error(void* user, RTCError code, const char* message) {
  auto* self = static_cast<EmbreeDevice*>(user);
  if (!self->pending_error_.empty()) self->pending_error_ += "; ";
  self->pending_error_ += "Embree error " + std::to_string(code) + ": " + (message ? message : "");
}

void EmbreeDevice::check(const char* what) const {
  if (pending_error_.empty()) return;
  std::string message = std::string(what) + ": " + pending_error_;
  pending_error_.clear();
  throw std::runtime_error(message);
}

EmbreeScene::EmbreeScene(const EmbreeDevice& device) {
  scene_ = rtcNewScene(device.get());
  device.check("rtcNewScene");
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
}

}  // namespace tessera

// Small model files written by the tests themselves, and the ways to read them.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "common/mesh_files/folder_scene_files.hpp"
#include "common/scene/scene_files.hpp"

namespace tessera::test {

class MeshFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("tessera-mesh-" + std::to_string(::getpid()) + "-" + info->test_suite_name() + "-" +
            info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::filesystem::path write(const std::string& name, std::string_view bytes) {
    const auto path = dir_ / name;
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return path;
  }

  Model load(const std::string& name, NormalsMode normals = NormalsMode::file,
             std::size_t max_triangles = 1000000) {
    MeshFileRequest request;
    request.file = name;
    request.format = *mesh_format_of(name);
    request.normals = normals;
    request.max_triangles = max_triangles;
    request.limit_max_triangles = max_triangles;
    return read_model_file(dir_ / name, request);
  }

  // The message of the SceneFileError that loading `name` throws, or "" when none is.
  std::string load_error(const std::string& name, std::size_t max_triangles = 1000000) {
    try {
      load(name, NormalsMode::file, max_triangles);
    } catch (const SceneFileError& e) {
      return e.what();
    }
    return "";
  }

  std::filesystem::path dir_;
};

}  // namespace tessera::test

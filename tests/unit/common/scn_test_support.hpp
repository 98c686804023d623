// Helpers shared by the .scn importer's tests: scene files written into a folder of the
// test's own, imported, and the error an import throws.
#pragma once

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/scn/scn_import.hpp"

namespace tessera::scn_test {

using nlohmann::json;

// A camera line for scenes that are about something else.
inline const std::string camera = "camera 0 0 5  0 0 -1  0 1 0  0.5  0.01 100\n";

class ScnImportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("tessera-scn-" + std::string(info->name()) + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Writes `text` to `name` (a path relative to the test's folder, folders made as needed).
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    const std::filesystem::path path = dir_ / name;
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }

  json import(const std::string& name, const ScnImportOptions& options = {}) const {
    return import_scn(dir_ / name, options);
  }

  // What importing `name` throws, or "" when it succeeds.
  std::string error_of(const std::string& name, const ScnImportOptions& options = {}) const {
    try {
      import_scn(dir_ / name, options);
    } catch (const ScnError& e) {
      return e.what();
    }
    return "";
  }

  // The start of an error message for `name` at `line`: "/tmp/.../scene.scn:12: ".
  std::string at(const std::string& name, std::size_t line) const {
    return (dir_ / name).string() + ":" + std::to_string(line) + ": ";
  }

  std::filesystem::path dir_;
};

}  // namespace tessera::scn_test

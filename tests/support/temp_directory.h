// Temporary files and directories of a test program. The suite runs hundreds
// of test programs and some of them write hundreds of MB (stores, photon
// tables): each path made here is removed when the program ends with every
// test passed. A failed test's files stay, for a look, and the program says
// where they are.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace portico::testing_support {

class TempPaths {
 public:
  static TempPaths& instance() {
    static TempPaths paths;
    return paths;
  }
  void add(const std::filesystem::path& path) {
    std::lock_guard<std::mutex> lock(mutex_);
    paths_.push_back(path);
  }
  ~TempPaths() {
    const bool passed = ::testing::UnitTest::GetInstance()->Passed();
    std::error_code ignored;
    for (const std::filesystem::path& path : paths_) {
      if (passed)
        std::filesystem::remove_all(path, ignored);
      else
        std::fprintf(stderr, "kept for a look: %s\n", path.c_str());
    }
  }

 private:
  std::mutex mutex_;
  std::vector<std::filesystem::path> paths_;
};

// /tmp/portico-NAME-PID (TMPDIR respected), removed first if a previous
// program of the same pid left it; `directory` creates it.
inline std::filesystem::path tempPath(const std::string& name, bool directory = true) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("portico-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(path);
  if (directory) std::filesystem::create_directories(path);
  TempPaths::instance().add(path);
  return path;
}

}  // namespace portico::testing_support

// A fixture for the model file tests: a directory of its own (TempDirTest), and the check that load_surfels refuses
// each of a list of broken files with its typed error under the field "path", naming the file and saying why.
#pragma once

#include <string>
#include <vector>

#include "expect_error.hpp"
#include "surfeledit/core/model_io.hpp"
#include "temp_dir_test.hpp"

namespace surfeledit::testing_util {

// A file load_surfels must refuse: its name and bytes, the error's code, and words its message must hold.
struct BrokenFile {
  const char* name;
  std::string bytes;
  ErrorCode code;
  const char* says;
};

class ModelFileTest : public TempDirTest {
 protected:
  // Writes each file into the directory and expects load_surfels to refuse it as stated.
  void expect_refused(const std::vector<BrokenFile>& files) const {
    for (const BrokenFile& k : files) {
      const std::string file = write(k.name, k.bytes);
      const std::string msg = expect_error([&] { load_surfels(file); }, k.code, "path");
      EXPECT_NE(msg.find(k.name), std::string::npos) << msg;
      EXPECT_NE(msg.find(k.says), std::string::npos) << k.name << ": " << msg;
    }
  }
};

}  // namespace surfeledit::testing_util

// A --cache-dir worker's store mirror against file chunks that name paths
// outside its cache: whatever answers on the coordinator's endpoint names
// the file, so only a store's own file names are written, under the cache,
// through no symbolic link.
#include "worker/store_mirror.h"

#include <capnp/message.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include "tests/integration/service_harness.h"

namespace portico {
namespace {

using namespace harness;

class StoreMirrorPaths : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = makeTempDirectory(std::string("store-mirror-") +
                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_ / "cache");
    fs::create_directories(dir_ / "elsewhere");
  }
  // What accept() says of a whole one-chunk file named `path` ("" when written).
  std::string accept(StoreMirror& mirror, const std::string& path) {
    capnp::MallocMessageBuilder message;
    auto chunk = message.initRoot<wire::FileChunk>();
    chunk.setStore("/srv/store");
    chunk.setPath(path);
    const std::string data = "planted";
    chunk.setTotalBytes(data.size());
    chunk.setData(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(data.data()), data.size()));
    try {
      mirror.accept(chunk.asReader());
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  }
  size_t filesOutsideTheCache() const {
    size_t count = 0;
    for (const auto& entry : fs::recursive_directory_iterator(dir_ / "elsewhere")) count += entry.is_regular_file();
    return count;
  }
  fs::path dir_;
};

TEST_F(StoreMirrorPaths, OnlyStoreFileNamesAreWrittenAndOnlyInsideTheCache) {
  StoreMirror mirror((dir_ / "cache").string());
  const fs::path local = mirror.localDirectory("/srv/store");
  for (const std::string& bad : std::vector<std::string>{"cells/../../../elsewhere/x", (dir_ / "elsewhere" / "x").string(),
                                "../elsewhere/x", "scene.db/../x", "cells/0.cell/../../x", "cells/x.cell",
                                "textures/../cells/0.cell", "other/0.cell", ""}) {
    const std::string error = accept(mirror, bad);
    EXPECT_NE(error.find("not a scene store file name"), std::string::npos) << bad << ": " << error;
  }
  EXPECT_EQ(accept(mirror, "cells/0.cell"), "");
  EXPECT_EQ(readFile(local / "cells" / "0.cell"), "planted");
  // A cells folder in the cache swapped for a link to elsewhere is not followed.
  fs::remove_all(local / "cells");
  fs::create_directory_symlink(dir_ / "elsewhere", local / "cells");
  EXPECT_NE(accept(mirror, "cells/1.cell").find("symbolic link"), std::string::npos);
  // Nor a part file planted as a link.
  fs::remove(local / "cells");
  fs::create_directories(local / "cells");
  fs::create_symlink(dir_ / "elsewhere" / "y", local / "cells" / "2.cell.part");
  EXPECT_NE(accept(mirror, "cells/2.cell"), "");
  EXPECT_EQ(filesOutsideTheCache(), 0u);
}

}  // namespace
}  // namespace portico

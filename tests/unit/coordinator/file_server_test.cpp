// The coordinator's file server against a store that tries to hand out
// files outside itself: symbolic links (to a file, to a directory), a
// FIFO, a directory, a store not in the allowed set.
#include "coordinator/file_server.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace portico {
namespace {

namespace fs = std::filesystem;

class FileServer : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("portico-file-server-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    store_ = dir_ / "store";
    fs::create_directories(store_ / "cells");
    std::ofstream(store_ / "scene.db") << "catalogue";
    std::ofstream(store_ / "cells" / "0.cell") << "cell zero";
    std::ofstream(dir_ / "secret.txt") << "TOP SECRET";
    fs::permissions(dir_ / "secret.txt", fs::perms::owner_read | fs::perms::owner_write);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The chunk served for `path` of `store` when `allowed` are the servable stores.
  static std::pair<std::string, std::string> fetch(const std::set<std::string>& allowed, const fs::path& store,
                                                   const std::string& path) {
    capnp::MallocMessageBuilder request, reply;
    auto fetch = request.initRoot<wire::FetchFile>();
    fetch.setStore(store.string());
    fetch.setPath(path);
    auto chunk = reply.initRoot<wire::FileChunk>();
    serveFileChunk(allowed, fetch.asReader(), chunk);
    auto data = chunk.asReader().getData();
    return {std::string(reinterpret_cast<const char*>(data.begin()), data.size()), chunk.asReader().getError()};
  }

  fs::path dir_, store_;
};

TEST_F(FileServer, ServesTheRegularFilesOfAnAllowedStore) {
  const std::set<std::string> allowed{store_.string()};
  EXPECT_EQ(fetch(allowed, store_, "scene.db"), std::make_pair(std::string("catalogue"), std::string()));
  EXPECT_EQ(fetch(allowed, store_, "cells/0.cell"), std::make_pair(std::string("cell zero"), std::string()));
}

TEST_F(FileServer, RefusesSymbolicLinksOutOfTheStore) {
  const std::set<std::string> allowed{store_.string()};
  fs::create_symlink(dir_ / "secret.txt", store_ / "cells" / "7.cell");
  auto [data, error] = fetch(allowed, store_, "cells/7.cell");
  EXPECT_EQ(data, "");
  EXPECT_NE(error.find("cells/7.cell: cannot open: a symbolic link"), std::string::npos) << error;
  // The catalogue too, and a cells directory that is a link to another one.
  fs::remove(store_ / "scene.db");
  fs::create_symlink(dir_ / "secret.txt", store_ / "scene.db");
  EXPECT_EQ(fetch(allowed, store_, "scene.db").first, "");
  const fs::path elsewhere = dir_ / "elsewhere";
  fs::create_directories(elsewhere);
  std::ofstream(elsewhere / "3.cell") << "TOP SECRET";
  fs::remove_all(store_ / "cells");
  fs::create_directory_symlink(elsewhere, store_ / "cells");
  std::tie(data, error) = fetch(allowed, store_, "cells/3.cell");
  EXPECT_EQ(data, "");
  EXPECT_NE(error.find("not a directory of the store"), std::string::npos) << error;
}

TEST_F(FileServer, RefusesWhatIsNotARegularFileAndStoresNotAllowed) {
  const std::set<std::string> allowed{store_.string()};
  ASSERT_EQ(::mkfifo((store_ / "cells" / "5.cell").c_str(), 0644), 0);
  EXPECT_NE(fetch(allowed, store_, "cells/5.cell").second.find("not a regular file"), std::string::npos);
  fs::create_directories(store_ / "cells" / "6.cell");
  EXPECT_NE(fetch(allowed, store_, "cells/6.cell").second.find("not a regular file"), std::string::npos);
  EXPECT_NE(fetch({}, store_, "scene.db").second.find("belongs to no active job"), std::string::npos);
  EXPECT_NE(fetch(allowed, store_, "../secret.txt").second.find("is not a scene store file"), std::string::npos);
}

}  // namespace
}  // namespace portico

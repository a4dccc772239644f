#include "common/net/curve_keys.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace portico {
namespace {

namespace fs = std::filesystem;

class CurveKeys : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("portico-keys-" + std::to_string(getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // The message of the error `load` throws ("" if none).
  template <typename Load>
  static std::string errorOf(Load load) {
    try {
      load();
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(CurveKeys, GeneratedKeysLoadOnBothSidesAndSecretsArePrivate) {
  net::generateKeys(dir_.string());
  const net::ServerKeys server = net::loadServerKeys(dir_.string());
  const net::ClientKeys client = net::loadClientKeys(dir_.string());
  EXPECT_EQ(client.serverPublicKey, server.server.publicKey);
  ASSERT_EQ(server.authorizedClients.size(), 1u);
  EXPECT_EQ(server.authorizedClients[0], client.client.publicKey);
  EXPECT_EQ(client.client.secretKey.size(), 40u);
  for (const char* secret : {"coordinator.secret", "client.secret"}) {
    struct stat info {};
    ASSERT_EQ(::stat((dir_ / secret).c_str(), &info), 0);
    EXPECT_EQ(info.st_mode & 0777, 0600u) << secret;
  }
}

TEST_F(CurveKeys, GenerateNeverOverwritesAKey) {
  net::generateKeys(dir_.string());
  const std::string error = errorOf([&] { net::generateKeys(dir_.string()); });
  EXPECT_NE(error.find("already exists"), std::string::npos) << error;
}

TEST_F(CurveKeys, SeveralAuthorizedClientKeysAndCommentsAreRead) {
  net::generateKeys(dir_.string());
  const fs::path other = dir_ / "other";
  net::generateKeys(other.string());
  {
    std::ofstream out(dir_ / "client.public", std::ios::app);
    out << "\n# a second worker pool\n  " << net::loadClientKeys(other.string()).client.publicKey << "  \n";
  }
  EXPECT_EQ(net::loadServerKeys(dir_.string()).authorizedClients.size(), 2u);
}

TEST_F(CurveKeys, AMissingFileIsNamedWithTheCommandThatWritesIt) {
  fs::create_directories(dir_);
  const std::string error = errorOf([&] { net::loadClientKeys(dir_.string()); });
  EXPECT_NE(error.find((dir_ / "coordinator.public").string() + ": cannot open"), std::string::npos) << error;
  EXPECT_NE(error.find("portico keys generate"), std::string::npos) << error;
}

TEST_F(CurveKeys, BadZ85IsRefusedNamingTheFileAndLine) {
  net::generateKeys(dir_.string());
  // 40 characters, but '"' is not in the Z85 alphabet; then a key of the wrong length.
  for (const std::string& bad : {std::string(39, 'a') + "\"", std::string("abc")}) {
    std::ofstream(dir_ / "client.secret", std::ios::trunc) << "# comment\n" << bad << "\n";
    const std::string error = errorOf([&] { net::loadClientKeys(dir_.string()); });
    EXPECT_NE(error.find((dir_ / "client.secret").string() + ": line 2 is not a 40-character Z85 CURVE key"),
              std::string::npos)
        << error;
  }
}

TEST_F(CurveKeys, EmptyFilesAndTwoSecretsAreRefused) {
  net::generateKeys(dir_.string());
  std::ofstream(dir_ / "client.public", std::ios::trunc) << "# nobody\n";
  EXPECT_NE(errorOf([&] { net::loadServerKeys(dir_.string()); }).find("holds no key"), std::string::npos);
  const std::string secret = net::loadClientKeys(dir_.string()).client.secretKey;
  std::ofstream(dir_ / "client.secret", std::ios::app) << secret << "\n";
  EXPECT_NE(errorOf([&] { net::loadClientKeys(dir_.string()); }).find("holds 2 keys, expected one"), std::string::npos);
}

TEST_F(CurveKeys, ACoordinatorPublicKeyThatDoesNotMatchItsSecretIsRefused) {
  net::generateKeys(dir_.string());
  net::generateKeys((dir_ / "other").string());
  fs::copy_file(dir_ / "other" / "coordinator.public", dir_ / "coordinator.public",
                fs::copy_options::overwrite_existing);
  const std::string error = errorOf([&] { net::loadServerKeys(dir_.string()); });
  EXPECT_NE(error.find("is not the public half of"), std::string::npos) << error;
}

}  // namespace
}  // namespace portico

#include "common/net/curve_keys.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <vector>

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

TEST_F(CurveKeys, EachRoleGetsItsOwnPairAndSecretsArePrivate) {
  EXPECT_EQ(net::generateKeys(dir_.string()), (std::vector<std::string>{"coordinator", "client", "worker", "operator"}));
  const net::ServerKeys server = net::loadServerKeys(dir_.string());
  ASSERT_EQ(server.authorized.size(), 3u);
  std::set<std::string> publicKeys;
  for (net::Role role : net::kAllRoles) {
    const net::ClientKeys client = net::loadClientKeys(dir_.string(), role);
    EXPECT_EQ(client.serverPublicKey, server.server.publicKey);
    ASSERT_TRUE(server.authorized.count(client.client.publicKey)) << net::roleName(role);
    EXPECT_EQ(server.authorized.at(client.client.publicKey), role);
    EXPECT_EQ(client.client.secretKey.size(), 40u);
    publicKeys.insert(client.client.publicKey);
  }
  EXPECT_EQ(publicKeys.size(), 3u);
  for (const char* secret : {"coordinator.secret", "client.secret", "worker.secret", "operator.secret"}) {
    struct stat info {};
    ASSERT_EQ(::stat((dir_ / secret).c_str(), &info), 0);
    EXPECT_EQ(info.st_mode & 0777, 0600u) << secret;
  }
  struct stat info {};
  ASSERT_EQ(::stat(dir_.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0700u);
}

TEST_F(CurveKeys, GenerateNeverOverwritesAKeyAndAddsTheMissingPairs) {
  net::generateKeys(dir_.string());
  const std::string before = net::loadClientKeys(dir_.string(), net::Role::Client).client.secretKey;
  // A directory of an older portico: the coordinator and client pairs only.
  for (const char* file : {"worker.public", "worker.secret", "operator.public", "operator.secret"}) fs::remove(dir_ / file);
  EXPECT_EQ(net::generateKeys(dir_.string()), (std::vector<std::string>{"worker", "operator"}));
  EXPECT_EQ(net::loadClientKeys(dir_.string(), net::Role::Client).client.secretKey, before);
  EXPECT_TRUE(net::generateKeys(dir_.string()).empty());
  fs::remove(dir_ / "worker.secret");
  const std::string error = errorOf([&] { net::generateKeys(dir_.string()); });
  EXPECT_NE(error.find("worker.public: exists without its other half worker.secret"), std::string::npos) << error;
}

TEST_F(CurveKeys, AKeyListedInTwoRolesIsRefused) {
  net::generateKeys(dir_.string());
  std::ofstream(dir_ / "worker.public", std::ios::app) << net::loadClientKeys(dir_.string(), net::Role::Client).client.publicKey << "\n";
  const std::string error = errorOf([&] { net::loadServerKeys(dir_.string()); });
  EXPECT_NE(error.find("is also listed in client.public"), std::string::npos) << error;
}

TEST_F(CurveKeys, DefaultKeysAreGeneratedOnceAndFoundOnlyForTcp) {
  const fs::path home = dir_ / "home";
  ::setenv("PORTICO_KEYS", (home / "keys").c_str(), 1);
  // None yet: a peer on tcp:// with no coordinator key could only reach an impostor.
  EXPECT_NE(errorOf([] { net::keysForEndpoint("", "tcp://127.0.0.1:5555"); }).find("no coordinator key to check it by"),
            std::string::npos);
  const std::string made = net::ensureDefaultKeys();
  EXPECT_EQ(made, (home / "keys").string());
  const std::string secret = net::loadClientKeys(made, net::Role::Worker).client.secretKey;
  EXPECT_EQ(net::ensureDefaultKeys(), made);
  EXPECT_EQ(net::loadClientKeys(made, net::Role::Worker).client.secretKey, secret);   // not regenerated
  EXPECT_EQ(net::keysForEndpoint("", "tcp://127.0.0.1:5555"), made);
  EXPECT_EQ(net::keysForEndpoint("", "ipc:///run/portico.sock"), "");
  EXPECT_EQ(net::keysForEndpoint("/etc/keys", "tcp://127.0.0.1:5555"), "/etc/keys");
  ::unsetenv("PORTICO_KEYS");
}

// As ssh: keys that another user could have written or swapped are refused.
TEST_F(CurveKeys, KeysOtherUsersCouldHavePutThereAreRefused) {
  net::generateKeys(dir_.string());
  fs::permissions(dir_ / "worker.secret", fs::perms::others_write, fs::perm_options::add);
  EXPECT_NE(errorOf([&] { net::loadClientKeys(dir_.string(), net::Role::Worker); })
                .find("key file " + (dir_ / "worker.secret").string() + ": writable by other users"),
            std::string::npos);
  fs::permissions(dir_ / "worker.secret", fs::perms::others_write, fs::perm_options::remove);
  fs::permissions(dir_, fs::perms::group_write, fs::perm_options::add);
  EXPECT_NE(errorOf([&] { net::loadServerKeys(dir_.string()); })
                .find("key directory " + dir_.string() + ": writable by other users"),
            std::string::npos);
  fs::permissions(dir_, fs::perms::group_write, fs::perm_options::remove);
  EXPECT_EQ(errorOf([&] { net::loadServerKeys(dir_.string()); }), "");
  // A folder above that anyone may write (not sticky): the keys could be swapped.
  const fs::path open = dir_ / "open";
  net::generateKeys((open / "keys").string());
  fs::permissions(open, fs::perms::all);
  EXPECT_NE(errorOf([&] { net::loadClientKeys((open / "keys").string(), net::Role::Client); })
                .find("folder above the key directory " + open.string() + ": writable by other users"),
            std::string::npos);
  fs::permissions(open, fs::perms::sticky_bit, fs::perm_options::add);   // as /tmp: no one moves another's entry
  EXPECT_EQ(errorOf([&] { net::loadClientKeys((open / "keys").string(), net::Role::Client); }), "");
  if (::geteuid() != 0) return;   // only root can give a file away
  ASSERT_EQ(::chown((dir_ / "client.public").c_str(), 65534, 65534), 0);
  EXPECT_NE(errorOf([&] { net::loadServerKeys(dir_.string()); })
                .find("key file " + (dir_ / "client.public").string() + ": owned by uid 65534, not by uid 0"),
            std::string::npos);
}

TEST_F(CurveKeys, SeveralAuthorizedClientKeysAndCommentsAreRead) {
  net::generateKeys(dir_.string());
  const fs::path other = dir_ / "other";
  net::generateKeys(other.string());
  {
    std::ofstream out(dir_ / "client.public", std::ios::app);
    out << "\n# a second worker pool\n  " << net::loadClientKeys(other.string(), net::Role::Client).client.publicKey << "  \n";
  }
  EXPECT_EQ(net::loadServerKeys(dir_.string()).authorized.size(), 4u);   // 2 clients, a worker, an operator
}

TEST_F(CurveKeys, AMissingFileIsNamedWithTheCommandThatWritesIt) {
  fs::create_directories(dir_);
  const std::string error = errorOf([&] { net::loadClientKeys(dir_.string(), net::Role::Client); });
  EXPECT_NE(error.find((dir_ / "coordinator.public").string() + ": cannot open"), std::string::npos) << error;
  EXPECT_NE(error.find("portico keys generate"), std::string::npos) << error;
}

TEST_F(CurveKeys, BadZ85IsRefusedNamingTheFileAndLine) {
  net::generateKeys(dir_.string());
  // 40 characters, but '"' is not in the Z85 alphabet; then a key of the wrong length.
  for (const std::string& bad : {std::string(39, 'a') + "\"", std::string("abc")}) {
    std::ofstream(dir_ / "client.secret", std::ios::trunc) << "# comment\n" << bad << "\n";
    const std::string error = errorOf([&] { net::loadClientKeys(dir_.string(), net::Role::Client); });
    EXPECT_NE(error.find((dir_ / "client.secret").string() + ": line 2 is not a 40-character Z85 CURVE key"),
              std::string::npos)
        << error;
  }
}

TEST_F(CurveKeys, EmptyFilesAndTwoSecretsAreRefused) {
  net::generateKeys(dir_.string());
  std::ofstream(dir_ / "client.public", std::ios::trunc) << "# nobody\n";
  EXPECT_NE(errorOf([&] { net::loadServerKeys(dir_.string()); }).find("holds no key"), std::string::npos);
  const std::string secret = net::loadClientKeys(dir_.string(), net::Role::Client).client.secretKey;
  std::ofstream(dir_ / "client.secret", std::ios::app) << secret << "\n";
  EXPECT_NE(errorOf([&] { net::loadClientKeys(dir_.string(), net::Role::Client); }).find("holds 2 keys, expected one"), std::string::npos);
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

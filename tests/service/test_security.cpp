// security_properties (surfeledit/service/security.hpp): the --security file -> DDS Security participant
// properties; every error names the file and the key or line. (The secured server itself is tested in
// tests/python/service/test_security.py.)
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>

#include "surfeledit/service/security.hpp"

using namespace surfeledit::service;

namespace {

namespace fs = std::filesystem;

// A directory with the six files and fake plugin libraries (parsing does not read them).
class SecurityConfig : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("surfeledit_security_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "user");
    fs::create_directories(dir_ / "ca");
    fs::create_directories(dir_ / "plugins");
    for (const char* f : {"ca/id.pem", "ca/perm.pem", "gov.p7s", "user/cert.pem", "user/key.pem", "user/perm.p7s",
                          "plugins/libdds_security_auth.so", "plugins/libdds_security_ac.so",
                          "plugins/libdds_security_crypto.so"}) {
      std::ofstream(dir_ / f) << "x";
    }
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes user/security.conf with the standard lines, `extra` appended, and `drop` left out.
  std::string write(const std::string& extra = "", const std::string& drop = "") {
    const std::string lines[] = {"identity_ca = ../ca/id.pem", "identity_certificate = cert.pem",
                                 "private_key = key.pem",      "permissions_ca = ../ca/perm.pem",
                                 "governance = ../gov.p7s",    "permissions = perm.p7s",
                                 "plugin_dir = ../plugins"};
    const fs::path conf = dir_ / "user" / "security.conf";
    std::ofstream out(conf);
    out << "# a comment\n\n";
    for (const auto& l : lines) {
      if (drop.empty() || l.rfind(drop + " ", 0) != 0) out << l << "\n";
    }
    out << extra;
    return conf.string();
  }

  std::string error_of(const std::string& conf) {
    try {
      (void)security_properties(conf);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no error)";
  }

  fs::path dir_;
};

TEST_F(SecurityConfig, MapsEveryFileToItsPropertyByAbsolutePath) {
  std::map<std::string, std::string> p;
  for (const auto& prop : security_properties(write())) p[prop.name] = prop.value;
  const auto canon = [&](const char* f) { return fs::canonical(dir_ / f).string(); };
  EXPECT_EQ(p.at("dds.sec.auth.identity_ca"), "file:" + canon("ca/id.pem"));
  EXPECT_EQ(p.at("dds.sec.auth.identity_certificate"), "file:" + canon("user/cert.pem"));
  EXPECT_EQ(p.at("dds.sec.auth.private_key"), "file:" + canon("user/key.pem"));
  EXPECT_EQ(p.at("dds.sec.access.permissions_ca"), "file:" + canon("ca/perm.pem"));
  EXPECT_EQ(p.at("dds.sec.access.governance"), "file:" + canon("gov.p7s"));
  EXPECT_EQ(p.at("dds.sec.access.permissions"), "file:" + canon("user/perm.p7s"));
  EXPECT_EQ(p.at("dds.sec.auth.library.path"), canon("plugins/libdds_security_auth.so"));
  EXPECT_EQ(p.at("dds.sec.access.library.path"), canon("plugins/libdds_security_ac.so"));
  EXPECT_EQ(p.at("dds.sec.crypto.library.path"), canon("plugins/libdds_security_crypto.so"));
  EXPECT_EQ(p.at("dds.sec.auth.library.init"), "init_authentication");
  EXPECT_EQ(p.at("dds.sec.access.library.finalize"), "finalize_access_control");
  EXPECT_EQ(p.size(), 15u);
}

TEST_F(SecurityConfig, ErrorsNameTheKeyOrLine) {
  EXPECT_NE(error_of(write("", "permissions")).find("missing key 'permissions'"), std::string::npos);
  EXPECT_NE(error_of(write("colour = red\n")).find("unknown key 'colour'"), std::string::npos);
  EXPECT_NE(error_of(write("private_key = key.pem\n")).find("'private_key' given twice"), std::string::npos);
  EXPECT_NE(error_of(write("just words\n")).find("line 10: expected 'key = value'"), std::string::npos);
  EXPECT_NE(error_of(write("", "governance") + "").find("missing key 'governance'"), std::string::npos);
  fs::remove(dir_ / "user" / "key.pem");
  EXPECT_NE(error_of(write()).find("private_key = 'key.pem' ("), std::string::npos);
  EXPECT_NE(error_of(write()).find("is not a readable regular file"), std::string::npos);
  EXPECT_NE(error_of((dir_ / "absent.conf").string()).find("cannot be read"), std::string::npos);
}

TEST_F(SecurityConfig, PluginsMustExist) {
  fs::remove(dir_ / "plugins" / "libdds_security_crypto.so");
  EXPECT_NE(error_of(write()).find("plugin_dir"), std::string::npos);
}

TEST_F(SecurityConfig, DirectoriesAreNotFiles) {
  fs::remove(dir_ / "gov.p7s");
  fs::create_directories(dir_ / "gov.p7s");
  EXPECT_NE(error_of(write()).find("governance"), std::string::npos);
}

}  // namespace

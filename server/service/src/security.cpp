#include "surfeledit/service/security.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#ifndef SURFELEDIT_DDS_SECURITY_PLUGIN_DIR
#define SURFELEDIT_DDS_SECURITY_PLUGIN_DIR ""
#endif

namespace surfeledit::service {

namespace {

namespace fs = std::filesystem;

// Configuration key -> Cyclone participant QoS property (OMG DDS Security, builtin plugins).
struct FileKey {
  const char* key;
  const char* property;
};
constexpr std::array<FileKey, 6> kFileKeys{{
    {"identity_ca", "dds.sec.auth.identity_ca"},
    {"identity_certificate", "dds.sec.auth.identity_certificate"},
    {"private_key", "dds.sec.auth.private_key"},
    {"permissions_ca", "dds.sec.access.permissions_ca"},
    {"governance", "dds.sec.access.governance"},
    {"permissions", "dds.sec.access.permissions"},
}};

// The three plugins: property prefix, library file, init and finalize functions.
struct Plugin {
  const char* prefix;
  const char* library;
  const char* init;
  const char* finalize;
};
constexpr std::array<Plugin, 3> kPlugins{{
    {"dds.sec.auth.library.", "libdds_security_auth.so", "init_authentication", "finalize_authentication"},
    {"dds.sec.crypto.library.", "libdds_security_crypto.so", "init_crypto", "finalize_crypto"},
    {"dds.sec.access.library.", "libdds_security_ac.so", "init_access_control", "finalize_access_control"},
}};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

[[noreturn]] void fail(const std::string& config, const std::string& what) {
  throw std::invalid_argument("security config '" + config + "': " + what);
}

// An absolute path to a readable regular file, or an error naming `key` and its `value` as given.
std::string regular_file(const std::string& config, const std::string& key, const std::string& value,
                         const fs::path& path) {
  std::error_code ec;
  const fs::path abs = fs::weakly_canonical(path, ec);
  struct stat st {};
  if (ec || ::stat(abs.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || ::access(abs.c_str(), R_OK) != 0) {
    fail(config, key + " = '" + value + "' (" + path.string() + ") is not a readable regular file");
  }
  return abs.string();
}

}  // namespace

std::vector<SecurityProperty> security_properties(const std::string& config_path) {
  std::ifstream in(config_path);
  if (!in) fail(config_path, "cannot be read");
  const fs::path base = fs::absolute(fs::path(config_path)).parent_path();
  std::map<std::string, std::string> values;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string text = trim(line);
    if (text.empty() || text[0] == '#') continue;
    const auto eq = text.find('=');
    const std::string where = "line " + std::to_string(number);
    if (eq == std::string::npos) fail(config_path, where + ": expected 'key = value', got '" + text + "'");
    const std::string key = trim(text.substr(0, eq));
    const std::string value = trim(text.substr(eq + 1));
    // `user` names the certificate's CN for clients (their id prefix); the server does not need it.
    bool known = key == "plugin_dir" || key == "user";
    for (const auto& k : kFileKeys) known = known || key == k.key;
    if (!known) fail(config_path, where + ": unknown key '" + key + "'");
    if (value.empty()) fail(config_path, where + ": empty value for '" + key + "'");
    if (!values.emplace(key, value).second) fail(config_path, where + ": '" + key + "' given twice");
  }
  std::vector<SecurityProperty> props;
  for (const auto& k : kFileKeys) {
    const auto it = values.find(k.key);
    if (it == values.end()) fail(config_path, std::string("missing key '") + k.key + "'");
    const fs::path p(it->second);
    const std::string file = regular_file(config_path, k.key, it->second, p.is_absolute() ? p : base / p);
    props.push_back({k.property, "file:" + file});
  }
  const auto dir_it = values.find("plugin_dir");
  fs::path plugin_dir(SURFELEDIT_DDS_SECURITY_PLUGIN_DIR);
  if (dir_it != values.end()) {
    plugin_dir = fs::path(dir_it->second);
    if (plugin_dir.is_relative()) plugin_dir = base / plugin_dir;
  }
  for (const auto& plugin : kPlugins) {
    const std::string lib = regular_file(config_path, "plugin_dir", plugin_dir.string(), plugin_dir / plugin.library);
    props.push_back({std::string(plugin.prefix) + "path", lib});
    props.push_back({std::string(plugin.prefix) + "init", plugin.init});
    props.push_back({std::string(plugin.prefix) + "finalize", plugin.finalize});
  }
  return props;
}

}  // namespace surfeledit::service

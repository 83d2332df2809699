#include "data_root.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <stdexcept>

#include "surfeledit/core/model_io.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit::service {

namespace {

namespace fs = std::filesystem;

constexpr const char* kField = "load_file.path";

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// `path` lies strictly below `root` (both canonical), compared component by component.
bool below(const fs::path& path, const fs::path& root) {
  auto p = path.begin();
  for (auto r = root.begin(); r != root.end(); ++r, ++p) {
    if (p == path.end() || *p != *r) return false;
  }
  return p != path.end();
}

// Closes a file descriptor on scope exit.
struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

DataRoot::DataRoot(const std::string& root, std::uint64_t max_bytes) : max_bytes_(max_bytes) {
  if (max_bytes == 0) throw std::invalid_argument("the file size limit must be positive");
  if (root.empty()) return;
  std::error_code ec;
  const fs::path canonical = fs::canonical(root, ec);
  if (ec || !fs::is_directory(canonical, ec)) {
    throw std::invalid_argument("data root '" + root + "' is not a directory");
  }
  root_ = canonical.string();
}

std::string DataRoot::resolve(const std::string& requested) const {
  if (!enabled()) {
    throw Error(ErrorCode::Conflict, kField,
                "file loading is off: the server runs without --data-root (upload the model instead)");
  }
  const std::string ext = lower_extension(requested);
  if (!loadable_extension(ext)) {
    throw Error(ErrorCode::InvalidArgument, kField,
                "'" + requested + "': unsupported extension '" + ext + "' (" + loadable_formats() + ")");
  }
  const Error hidden(ErrorCode::NotFound, kField,
                     "'" + requested + "': no such file below the server's data root");
  if (requested.find('\0') != std::string::npos) throw hidden;
  const fs::path given(requested);
  const fs::path joined = given.is_absolute() ? given : fs::path(root_) / given;
  std::error_code ec;
  const fs::path resolved = fs::canonical(joined, ec);  // every symlink and .. resolved; fails if missing
  if (ec || !below(resolved, fs::path(root_))) throw hidden;
  // Non-blocking and without following a (swapped-in) final symlink: a FIFO must not stall the server.
  const Fd file{::open(resolved.c_str(), O_RDONLY | O_NONBLOCK | O_NOFOLLOW | O_CLOEXEC)};
  if (file.fd < 0) throw hidden;
  struct stat st {};
  if (::fstat(file.fd, &st) != 0) throw hidden;
  if (!S_ISREG(st.st_mode)) {
    throw Error(ErrorCode::InvalidArgument, kField, "'" + requested + "': not a regular file");
  }
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes_) {
    throw Error(ErrorCode::TooLarge, kField,
                "'" + requested + "' is " + std::to_string(st.st_size) + " bytes, beyond the server's limit of " +
                    std::to_string(max_bytes_) + " (--max-file-mb)");
  }
  return resolved.string();
}

}  // namespace surfeledit::service

// Where OP_LOAD_FILE may read (docs/hardening.md, "Files"): regular files below the server's data root
// (--data-root), of at most a size limit (--max-file-mb). Without a data root, file loading is off.
#pragma once

#include <cstdint>
#include <string>

namespace surfeledit::service {

class DataRoot {
 public:
  // `root` empty: file loading off. Otherwise it must name a directory (std::invalid_argument if not);
  // it is resolved once (symlinks, ..) here. `max_bytes`: the largest file accepted.
  DataRoot(const std::string& root, std::uint64_t max_bytes);

  bool enabled() const { return !root_.empty(); }
  const std::string& root() const { return root_; }
  std::uint64_t max_bytes() const { return max_bytes_; }

  // The resolved path of `requested` (relative paths are taken below the root). Errors, all naming
  // "load_file.path" and quoting `requested` as given, never the resolved path:
  //  - loading off: Conflict ("file loading is off: the server runs without --data-root");
  //  - not .ply/.pcd/.obj: InvalidArgument (decided on the name alone, before any file system access);
  //  - missing, unreadable, or resolving outside the root (symlinks and .. followed): NotFound, ONE
  //    message for all of them, so that a reply never tells whether a path outside the root exists;
  //  - not a regular file (a directory, a FIFO, a device): InvalidArgument, without opening it for data
  //    (a FIFO is opened non-blocking, so it never stalls the server);
  //  - larger than max_bytes: TooLarge.
  std::string resolve(const std::string& requested) const;

 private:
  std::string root_;  // canonical, without a trailing separator; empty: off
  std::uint64_t max_bytes_;
};

}  // namespace surfeledit::service

#include "core/file_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.h"

namespace foresight {

void WriteFileBytes(const std::string& path, const char* data, std::size_t size) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0666);  // less the umask
  FS_THROW_UNLESS(fd >= 0, path, ": cannot create (", std::strerror(errno), ")");
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      ::close(fd);
      Fail(path, ": cannot write (", std::strerror(err), ")");
    }
    done += static_cast<std::size_t>(n);
  }
  const int sync_error = ::fsync(fd) == 0 ? 0 : errno;
  const int close_error = ::close(fd) == 0 ? 0 : errno;
  const int err = sync_error ? sync_error : close_error;
  FS_THROW_UNLESS(err == 0, path, ": cannot write (", std::strerror(err), ")");
}

namespace {
/// Flushes the directory entry of `path` after a rename; best effort, as some file systems
/// refuse to sync a directory.
void SyncParentDirectory(const std::string& path) {
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}
}  // namespace

namespace {
/// The file an atomic write replaces: `path`, or the file a symbolic link at `path` points to (the
/// link stays). Refuses an existing target that is not a regular file (a device such as
/// /dev/full, a directory, a socket): renaming over it would replace it.
std::string ReplacedFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path target = path;
  for (int hops = 0; fs::is_symlink(fs::symlink_status(target, ec)); ++hops) {
    FS_THROW_UNLESS(hops < 40, path, ": too many levels of symbolic links");
    const fs::path next = fs::read_symlink(target, ec);
    FS_THROW_UNLESS(!ec, path, ": cannot read the symbolic link (", ec.message(), ")");
    target = next.is_absolute() ? next : target.parent_path() / next;
  }
  const fs::file_status st = fs::status(target, ec);
  FS_THROW_UNLESS(!fs::exists(st) || fs::is_regular_file(st), path,
                  ": exists and is not a regular file (a device, directory or socket); "
                  "refusing to replace it, give a file path");
  return target.string();
}
}  // namespace

void WriteThroughTemporary(const std::string& path_given,
                           const std::function<void(const std::string& tmp)>& write) {
  const std::string path = ReplacedFile(path_given);
  const std::string tmp = path + ".tmp";
  try {
    write(tmp);
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    Fail(path, ": cannot move the written file into place (", std::strerror(err), ")");
  }
  SyncParentDirectory(path);
}

void WriteFileAtomically(const std::string& path, const std::string& bytes) {
  WriteThroughTemporary(
      path, [&](const std::string& tmp) { WriteFileBytes(tmp, bytes.data(), bytes.size()); });
}

}  // namespace foresight

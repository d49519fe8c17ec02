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
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
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

void WriteThroughTemporary(const std::string& path,
                           const std::function<void(const std::string& tmp)>& write) {
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

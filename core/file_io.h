#pragma once
/// Checked writes of whole files: every failure (a full disk, a read-only directory) is an Error
/// naming the file, and nothing half-written is left where a complete file is expected.

#include <cstddef>
#include <string>

namespace foresight {

/// Writes `size` bytes to `path` (created or truncated) and flushes them to disk.
void WriteFileBytes(const std::string& path, const char* data, std::size_t size);

/// Flushes the directory entry of `path` (after a rename); best effort, as some file systems
/// refuse to sync a directory.
void SyncParentDirectory(const std::string& path);

/// Writes `bytes` to path.tmp, flushes it, then renames it to `path` (the directory entry is
/// flushed too); on failure the temporary file is removed and `path` is left as it was.
void WriteFileAtomically(const std::string& path, const std::string& bytes);

}  // namespace foresight

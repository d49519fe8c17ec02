#pragma once
/// Checked writes of whole files: every failure (a full disk, a read-only directory) is an Error
/// naming the file, and nothing half-written is left where a complete file is expected.

#include <cstddef>
#include <functional>
#include <string>

namespace foresight {

/// Writes `size` bytes to `path` (created or truncated) and flushes them to disk.
void WriteFileBytes(const std::string& path, const char* data, std::size_t size);

/// `write` fills the temporary file it is given (path.tmp), which is then renamed to `path` and
/// the directory entry flushed; on any failure the temporary file is removed, `path` is left as
/// it was and the Error propagates. A symbolic link at `path` is written through (the file it
/// points to is replaced, the link stays); an existing `path` that is not a regular file (e.g.
/// /dev/full, a directory) is refused. Every atomic writer goes through this.
void WriteThroughTemporary(const std::string& path,
                           const std::function<void(const std::string& tmp)>& write);

/// WriteThroughTemporary of `bytes` with WriteFileBytes.
void WriteFileAtomically(const std::string& path, const std::string& bytes);

}  // namespace foresight

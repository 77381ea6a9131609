#pragma once
// Files that appear under their final name only when complete: written to a temporary file in
// the same folder, then renamed (atomic on POSIX), so a crash, a full disk or a reader at the
// wrong moment never sees half a file.
#include <string>

namespace polarslam {

/// The temporary file `path` is written to before commitTemporary().
std::string temporaryPathFor(const std::string& path);
/// Renames the finished temporary file to `path`; throws std::runtime_error naming both.
void commitTemporary(const std::string& temporary, const std::string& path);
/// Writes `content` to `path` atomically. Throws std::runtime_error naming the file on failure
/// (the temporary file is removed, an existing `path` is left as it was).
void writeFileAtomically(const std::string& path, const std::string& content);

}  // namespace polarslam

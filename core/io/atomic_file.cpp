#include "io/atomic_file.hpp"

#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace polarslam {

std::string temporaryPathFor(const std::string& path) { return path + ".tmp"; }

void commitTemporary(const std::string& temporary, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) throw std::runtime_error("cannot rename '" + temporary + "' to '" + path + "': " + ec.message());
}

void writeFileAtomically(const std::string& path, const std::string& content) {
  const std::string temporary = temporaryPathFor(path);
  bool written = false;
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write '" + path + "'");
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    written = static_cast<bool>(out);
  }
  if (!written) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw std::runtime_error("write failed on '" + path + "'");
  }
  commitTemporary(temporary, path);
}

}  // namespace polarslam

#pragma once
// Real test data from Debian's libcgal-demo, extracted at test time (never committed).

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

namespace tbs::test {

/// Extracts `members` (space-separated paths inside data.tar.gz, e.g. "data/meshes/head.off")
/// into a folder under the temporary directory named `folder` and returns that folder; nullopt
/// when libcgal-demo is not installed or tar fails.
inline std::optional<std::filesystem::path> cgal_demo_data(const std::string& folder, const std::string& members) {
  const std::string tarball = "/usr/share/doc/libcgal-dev/data.tar.gz";
  if (!std::filesystem::exists(tarball)) return std::nullopt;
  const auto dir = std::filesystem::temp_directory_path() / folder;
  std::filesystem::create_directories(dir);
  const std::string cmd = "tar xzf " + tarball + " -C '" + dir.string() + "' " + members;
  if (std::system(cmd.c_str()) != 0) return std::nullopt;
  return dir;
}

}  // namespace tbs::test

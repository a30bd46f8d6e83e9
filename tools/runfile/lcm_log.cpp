#include "tools/runfile/lcm_log.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace rigctl {

void check_is_lcm_log(const std::string& path, const std::string& tool) {
  auto fail = [&](const std::string& reason) { throw std::runtime_error(tool + ": '" + path + "': " + reason); };
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail("no such file");
  if (!std::filesystem::is_regular_file(path, ec)) fail("not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(std::string("cannot open: ") + std::strerror(errno));
  unsigned char magic[4] = {};
  in.read(reinterpret_cast<char*>(magic), 4);
  if (in.gcount() < 4) fail("not an LCM log (empty or truncated)");
  if (magic[0] != 0xED || magic[1] != 0xA1 || magic[2] != 0xDA || magic[3] != 0x01) {
    fail("not an LCM log (no LCM event sync word at the start)");
  }
}

}  // namespace rigctl

#include "tools/procedure/recovery_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace rigctl {

namespace {

static_assert(std::is_trivially_copyable_v<ProcedureRecovery>, "a recovery is written as its bytes");

constexpr const char* kMagic = "RIGCTL-RECOVERY 1";

uint64_t fnv1a(const char* p, std::size_t n) {
  uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(p[i]);
    h *= 1099511628211ull;
  }
  return h;
}

void write_all(int fd, const std::string& bytes, const std::string& path) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error("recovery: writing '" + path + "' failed: " + std::strerror(errno));
    done += static_cast<std::size_t>(n);
  }
}

void fsync_dir(const std::string& path) {
  const auto dir = std::filesystem::path(path).parent_path();
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

void write_recovery_file(const std::string& path, const RecoveryIdentity& id, const ProcedureRecovery& r) {
  const char* bytes = reinterpret_cast<const char*>(&r);
  std::ostringstream head;
  const ProcedureStatus& s = r.status;
  head << kMagic << "\nprocedure: " << id.procedure_path << "\nprocedure_hash: " << id.procedure_hash
       << "\nconfig: " << id.config_path << "\nconfig_hash: " << id.config_hash << "\nsequence: " << r.sequence
       << "\nstep: " << s.step << "\nphase: " << to_string(s.phase) << "\nstep_cycles: " << s.step_cycles
       << "\ntotal_cycles: " << s.total_cycles << "\nramp_in_cycles: " << s.ramp_in_cycles << "\nrow: " << s.row
       << "\nrow_cycles: " << s.row_cycles << "\npass: " << s.pass << "\nbytes: " << sizeof r << "\nchecksum: " << std::hex << fnv1a(bytes, sizeof r)
       << std::dec << "\n---\n";
  std::string out = head.str();
  out.append(bytes, sizeof r);
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("recovery: cannot write '" + tmp + "': " + std::strerror(errno));
  try {
    write_all(fd, out, tmp);
    if (::fsync(fd) != 0) throw std::runtime_error("recovery: fsync of '" + tmp + "' failed: " + std::strerror(errno));
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    throw std::runtime_error("recovery: cannot rename '" + tmp + "' to '" + path + "': " + std::strerror(errno));
  }
  fsync_dir(path);  // the rename itself survives a power cut
}

RecoveryFile read_recovery_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("recovery: cannot read '" + path + "'");
  std::string line;
  if (!std::getline(f, line) || line != kMagic) throw std::runtime_error("recovery: '" + path + "' is not a rigctl recovery file");
  RecoveryFile out;
  std::size_t size = 0;
  uint64_t checksum = 0;
  bool have_checksum = false;
  int number = 1;
  while (std::getline(f, line) && line != "---") {
    ++number;
    const auto colon = line.find(": ");
    if (colon == std::string::npos) throw std::runtime_error("recovery: " + path + ":" + std::to_string(number) + ": expected 'key: value'");
    const std::string key = line.substr(0, colon), value = line.substr(colon + 2);
    if (key == "procedure") out.identity.procedure_path = value;
    if (key == "procedure_hash") out.identity.procedure_hash = value;
    if (key == "config") out.identity.config_path = value;
    if (key == "config_hash") out.identity.config_hash = value;
    if (key == "bytes") size = std::stoull(value);
    if (key == "checksum") {
      checksum = std::stoull(value, nullptr, 16);
      have_checksum = true;
    }
  }
  if (line != "---" || size != sizeof(ProcedureRecovery) || !have_checksum) {
    throw std::runtime_error("recovery: '" + path + "' has no recovery of this rigctl's size (" +
                             std::to_string(sizeof(ProcedureRecovery)) + " bytes; the file says " + std::to_string(size) + ")");
  }
  std::string bytes(size, '\0');
  if (!f.read(bytes.data(), static_cast<std::streamsize>(size)) || f.peek() != std::char_traits<char>::eof()) {
    throw std::runtime_error("recovery: '" + path + "' is cut short or has bytes after its recovery");
  }
  if (fnv1a(bytes.data(), size) != checksum) throw std::runtime_error("recovery: '" + path + "' fails its checksum");
  std::memcpy(&out.recovery, bytes.data(), size);
  return out;
}

void check_recovery_identity(const RecoveryFile& file, const RecoveryIdentity& now, const std::string& path) {
  if (file.identity.procedure_hash != now.procedure_hash) {
    throw std::runtime_error("--resume: '" + path + "' was written for procedure " + file.identity.procedure_path + " (hash " +
                             file.identity.procedure_hash + "), not " + now.procedure_path + " (hash " + now.procedure_hash + ")");
  }
  if (file.identity.config_hash != now.config_hash) {
    throw std::runtime_error("--resume: '" + path + "' was written for config " + file.identity.config_path + " (hash " +
                             file.identity.config_hash + "), not " + now.config_path + " (hash " + now.config_hash + ")");
  }
}

}  // namespace rigctl

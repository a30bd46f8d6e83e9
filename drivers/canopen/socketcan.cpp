#include "drivers/canopen/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace rigctl {

namespace {

[[noreturn]] void fail(const std::string& interface, const std::string& what, int e, int fd = -1) {
  if (fd >= 0) ::close(fd);
  std::string msg = "socketcan: " + what + " for CAN interface '" + interface + "': " + std::strerror(e);
  if (e == EAFNOSUPPORT) {
    msg += " (this kernel has no CAN support: address family AF_CAN is unavailable; load the can and can_raw "
           "modules, or use canopen.socket_path with the simulated valve)";
  } else if (e == ENODEV) {
    msg += " (no such network interface; check `ip link show " + interface + "`)";
  }
  throw std::runtime_error(msg);
}

}  // namespace

CanTransport open_socketcan(const std::string& interface, std::span<const uint32_t> cob_ids) {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    throw std::runtime_error("socketcan: CAN interface name '" + interface + "' must be 1 to " +
                             std::to_string(IFNAMSIZ - 1) + " characters");
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) fail(interface, "cannot open a CAN_RAW socket", errno);

  const unsigned index = if_nametoindex(interface.c_str());
  if (index == 0) fail(interface, "cannot find the interface", errno, fd);

  // Exact match on the 11-bit id and on the EFF and RTR flags: only standard
  // data frames of this node's COB-IDs reach the driver.
  std::vector<can_filter> filters;
  for (const uint32_t id : cob_ids) filters.push_back({id & CAN_SFF_MASK, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG});
  const void* data = filters.empty() ? nullptr : filters.data();
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, data, static_cast<socklen_t>(filters.size() * sizeof(can_filter))) != 0) {
    fail(interface, "cannot set the receive filters (CAN_RAW_FILTER)", errno, fd);
  }

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) fail(interface, "cannot bind", errno, fd);
  return CanTransport(fd, "socketcan:" + interface);
}

}  // namespace rigctl

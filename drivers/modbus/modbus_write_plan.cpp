#include "drivers/modbus/modbus_write_plan.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>

namespace rigctl {

WritePlan plan_writes(std::span<const ModbusPoint> points) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    const ModbusPoint& p = points[i];
    const std::string where = "output " + std::to_string(i) + ": ";
    if (p.type != RegisterType::kHoldingRegister) {
      throw std::invalid_argument(where + "outputs must be holding registers (written with FC 6/16)");
    }
    if (p.unit_id < 0 || p.unit_id > 255) {
      throw std::invalid_argument(where + "unit id must be in 0..255, got " + std::to_string(p.unit_id));
    }
    if (p.address < 0 || p.address + register_count(p.format) - 1 > 65535) {
      throw std::invalid_argument(where + "address " + std::to_string(p.address) + " outside 0..65535");
    }
  }

  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::tuple(points[a].unit_id, points[a].address) < std::tuple(points[b].unit_id, points[b].address);
  });

  WritePlan plan;
  plan.where.resize(points.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const ModbusPoint& p = points[order[k]];
    const int n = register_count(p.format);
    if (!plan.blocks.empty()) {
      WriteBlock& b = plan.blocks.back();
      const int end = b.address + b.count;  // one past the block's last register
      if (b.unit_id == p.unit_id && p.address < end) {
        throw std::invalid_argument("output " + std::to_string(order[k]) + ": register " +
                                    std::to_string(p.address) + " of unit " + std::to_string(p.unit_id) +
                                    " is already written by output " + std::to_string(order[k - 1]));
      }
      if (b.unit_id == p.unit_id && p.address == end && b.count + n <= kMaxWriteRegisters) {
        plan.where[order[k]] = {static_cast<int>(plan.blocks.size()) - 1, b.count};
        b.count += n;
        continue;
      }
    }
    plan.blocks.push_back({p.unit_id, p.address, n});
    plan.where[order[k]] = {static_cast<int>(plan.blocks.size()) - 1, 0};
  }
  return plan;
}

}  // namespace rigctl

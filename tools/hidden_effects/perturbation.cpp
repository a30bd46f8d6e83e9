#include "tools/hidden_effects/perturbation.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace rigctl {

void Perturbation::scale(const std::string& name, double& value, double tol) {
  if (!active()) return;
  const double t = tol < 0.0 ? tolerance_ : tol;
  const double f = uniform(1.0 - t, 1.0 + t);
  drawn_[name] = f;
  value *= f;
}

double Perturbation::factor(const std::string& name, double lo, double hi) {
  if (!active()) return 1.0;
  const double f = uniform(lo, hi);
  drawn_[name] = f;
  return f;
}

int Perturbation::pick(const std::string& name, int n) {
  if (!active() || n <= 1) return 0;
  const int k = std::min(n - 1, static_cast<int>(uniform(0.0, static_cast<double>(n))));
  drawn_[name] = k;
  return k;
}

void write_varied_demand(const std::string& in, const std::string& column, const std::string& out, double amplitude,
                         double stretch) {
  std::ifstream f(in);
  if (!f) throw std::runtime_error("cannot read the demand table '" + in + "'");
  std::string line, header;
  std::vector<std::string> comments;
  std::vector<double> t, x;
  int col = -1;
  while (std::getline(f, line)) {
    if (line.empty()) continue;
    if (line[0] == '#') {
      comments.push_back(line);
      continue;
    }
    std::stringstream ss(line);
    std::string cell;
    std::vector<std::string> cells;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (header.empty()) {
      header = line;
      for (std::size_t i = 0; i < cells.size(); ++i)
        if (cells[i] == column) col = static_cast<int>(i);
      if (col < 1) throw std::runtime_error("demand table '" + in + "' has no column '" + column + "'");
      continue;
    }
    t.push_back(std::stod(cells.at(0)));
    x.push_back(std::stod(cells.at(static_cast<std::size_t>(col))));
  }
  if (t.size() < 2) throw std::runtime_error("demand table '" + in + "' has fewer than two rows");
  const double step = t[1] - t[0], end = t.back() * stretch;
  std::ofstream o(out);
  if (!o) throw std::runtime_error("cannot write the demand table '" + out + "'");
  o << "# varied copy of " << in << ": amplitude x " << amplitude << ", time x " << stretch << "\n";
  o << "t," << column << "\n";
  std::size_t j = 0;
  for (std::size_t k = 0;; ++k) {
    const double tk = static_cast<double>(k) * step;
    if (tk > end + 1e-12) break;
    const double src = tk / stretch;
    while (j + 2 < t.size() && t[j + 1] < src) ++j;
    const double a = std::clamp((src - t[j]) / (t[j + 1] - t[j]), 0.0, 1.0);
    o << tk << "," << amplitude * (x[j] + a * (x[j + 1] - x[j])) << "\n";
  }
  if (!o) throw std::runtime_error("writing the demand table '" + out + "' failed");
}

}  // namespace rigctl

#include "plant/two_poster/two_poster_plant.hpp"

#include <algorithm>
#include <cmath>

namespace rigctl {

namespace {

// Body state indices: z_s, phi, z_u1, z_u2, then their rates.
constexpr std::size_t kZs = 0, kPhi = 1, kZu = 2, kVs = 4, kOmega = 5, kVu = 6;

TwoPosterPlant::State axpy(const TwoPosterPlant::State& y, double h, const TwoPosterPlant::State& k) {
  TwoPosterPlant::State out = y;
  for (std::size_t i = 0; i < out.body.size(); ++i) out.body[i] += h * k.body[i];
  for (std::size_t p = 0; p < 2; ++p) {
    for (std::size_t i = 0; i < out.posts[p].size(); ++i) out.posts[p][i] += h * k.posts[p][i];
  }
  return out;
}

}  // namespace

TwoPosterPlant::TwoPosterPlant(const TwoPosterParams& params) : params_(params) {
  const auto& c = params_.car;
  lever_ = {c.dist_front, -c.dist_rear};
  const double wheelbase = c.dist_front + c.dist_rear;
  static_tyre_ = {(c.mass_body * c.dist_rear / wheelbase + c.mass_unsprung_1) * c.gravity,
                  (c.mass_body * c.dist_front / wheelbase + c.mass_unsprung_2) * c.gravity};
  signals_ = {{"z_r1", "m"},  {"z_r2", "m"},  {"z_u1", "m"},  {"z_u2", "m"},      {"z_s", "m"},       {"phi", "rad"},
              {"a_s1", "m/s^2"}, {"a_s2", "m/s^2"}, {"p1_1", "Pa"}, {"p2_1", "Pa"}, {"p1_2", "Pa"}, {"p2_2", "Pa"},
              {"sim_v_r1", "m/s"}, {"sim_v_r2", "m/s"}, {"sim_x_s1", "1"}, {"sim_x_s2", "1"}};
  commands_ = {{"u_1", "1"}, {"u_2", "1"}};
  reset();
}

double TwoPosterPlant::static_load(int post) const {
  const auto p = static_cast<std::size_t>(post);
  return static_tyre_[p] + params_.posts[p].mass_platen * params_.car.gravity;
}

double TwoPosterPlant::rest_command(int post) const {
  return post_rest(params_.posts[static_cast<std::size_t>(post)], static_load(post))[post::kXs];
}

void TwoPosterPlant::reset() {
  state_ = State{};
  for (int p = 0; p < 2; ++p) state_.posts[static_cast<std::size_t>(p)] = post_rest(params_.posts[static_cast<std::size_t>(p)], static_load(p));
}

double TwoPosterPlant::tyre_force(const State& s, int wheel) const {
  const auto w = static_cast<std::size_t>(wheel);
  const auto& c = params_.car;
  const double k = w == 0 ? c.tyre_stiffness_1 : c.tyre_stiffness_2;
  const double d = w == 0 ? c.tyre_damping_1 : c.tyre_damping_2;
  const double deviation = k * (s.posts[w][post::kXr] - s.body[kZu + w]) + d * (s.posts[w][post::kVr] - s.body[kVu + w]);
  return std::max(deviation, -static_tyre_[w]);  // the tyre leaves the platen: no pull
}

std::array<double, 2> TwoPosterPlant::corner_forces(const State& s) const {
  const auto& c = params_.car;
  std::array<double, 2> f{};
  for (std::size_t i = 0; i < 2; ++i) {
    const double corner = s.body[kZs] + lever_[i] * s.body[kPhi];
    const double corner_rate = s.body[kVs] + lever_[i] * s.body[kOmega];
    const double k = i == 0 ? c.spring_1 : c.spring_2;
    const double b = i == 0 ? c.damper_1 : c.damper_2;
    const double extension_rate = corner_rate - s.body[kVu + i];
    const double damping = b * (extension_rate > 0.0 ? c.damper_rebound_factor : 1.0) * extension_rate;
    f[i] = k * (s.body[kZu + i] - corner) - damping;
  }
  return f;
}

TwoPosterPlant::State TwoPosterPlant::derivative(const State& s, const std::array<double, 2>& u) const {
  const auto& c = params_.car;
  const auto f = corner_forces(s);
  State d;
  for (std::size_t i = 0; i < 4; ++i) d.body[i] = s.body[i + 4];
  d.body[kVs] = (f[0] + f[1]) / c.mass_body;
  d.body[kOmega] = (lever_[0] * f[0] + lever_[1] * f[1]) / c.inertia_body;
  const std::array<double, 2> m_u{c.mass_unsprung_1, c.mass_unsprung_2};
  for (std::size_t i = 0; i < 2; ++i) {
    const double tyre = tyre_force(s, static_cast<int>(i));
    d.body[kVu + i] = (tyre - f[i]) / m_u[i];
    const double load = static_load(static_cast<int>(i)) + tyre;
    d.posts[i] = post_derivatives(params_.posts[i], s.posts[i], u[i], load);
  }
  return d;
}

void TwoPosterPlant::rk4(const std::array<double, 2>& u, double h) {
  const State k1 = derivative(state_, u);
  const State k2 = derivative(axpy(state_, 0.5 * h, k1), u);
  const State k3 = derivative(axpy(state_, 0.5 * h, k2), u);
  const State k4 = derivative(axpy(state_, h, k3), u);
  state_ = axpy(state_, h / 6.0, k1);
  state_ = axpy(state_, h / 3.0, k2);
  state_ = axpy(state_, h / 3.0, k3);
  state_ = axpy(state_, h / 6.0, k4);
  for (std::size_t p = 0; p < 2; ++p) post_floors(params_.posts[p], state_.posts[p]);
}

void TwoPosterPlant::advance(std::span<const double> command, double dt) {
  std::array<double, 2> u{};
  for (std::size_t i = 0; i < 2; ++i) {
    const double v = i < command.size() ? command[i] : 0.0;
    u[i] = std::isfinite(v) ? std::clamp(v, -1.0, 1.0) : 0.0;  // the valve amplifier saturates there
  }
  const int steps = std::max(1, static_cast<int>(std::ceil(dt / params_.substep_s - 1e-9)));
  for (int i = 0; i < steps; ++i) rk4(u, dt / steps);
}

void TwoPosterPlant::measure(std::span<double> out) const {
  namespace sig = two_poster_signal;
  const auto& s = state_;
  const auto f = corner_forces(s);
  const double heave_acc = (f[0] + f[1]) / params_.car.mass_body;
  const double pitch_acc = (lever_[0] * f[0] + lever_[1] * f[1]) / params_.car.inertia_body;
  out[sig::kZr1] = s.posts[0][post::kXr];
  out[sig::kZr2] = s.posts[1][post::kXr];
  out[sig::kZu1] = s.body[kZu];
  out[sig::kZu2] = s.body[kZu + 1];
  out[sig::kZs] = s.body[kZs];
  out[sig::kPhi] = s.body[kPhi];
  out[sig::kAs1] = heave_acc + lever_[0] * pitch_acc;
  out[sig::kAs2] = heave_acc + lever_[1] * pitch_acc;
  out[sig::kP1a] = s.posts[0][post::kP1];
  out[sig::kP2a] = s.posts[0][post::kP2];
  out[sig::kP1b] = s.posts[1][post::kP1];
  out[sig::kP2b] = s.posts[1][post::kP2];
  out[sig::kSimVr1] = s.posts[0][post::kVr];
  out[sig::kSimVr2] = s.posts[1][post::kVr];
  out[sig::kSimXs1] = s.posts[0][post::kXs];
  out[sig::kSimXs2] = s.posts[1][post::kXs];
}

}  // namespace rigctl

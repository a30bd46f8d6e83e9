// A half car on a two-poster road simulator: the half vehicle of seed 001
// (plant/half_car/half_car_params.hpp: body in heave and pitch, two
// unsprung masses, springs, dampers, tyres, wheelbase a + b) with each
// tyre standing on the platen of a hydraulic post like the quarter car's
// (plant/two_poster/hydraulic_post.hpp). Post 1 is under the front axle
// (lever arm a), post 2 under the rear (-b). Every post moves both ends of
// the body: the pitch and heave modes couple the two drives, which is what
// MIMO drive iteration is for. Equations and parameters: docs/rig-models.md
// section 4.
//
// Body and wheels are deviations from static equilibrium; each post
// carries its axle's static load (the body's share by the lever rule, the
// wheel, the platen) plus the tyre's deviation force, and a tyre leaves its
// platen (force zero) when the deviation would pull it down. Integrated
// with RK4 in fixed sub-steps of 0.125 ms: the stiffest mode, the platen
// (5 kg) on its oil columns (beta A1^2 / V1 about 1.1e8 N/m near home), is
// about 4.7e3 rad/s, so h w = 0.6, well inside RK4's stability bound (2.8).
#pragma once

#include <array>
#include <vector>

#include "plant/half_car/half_car_params.hpp"
#include "plant/simulated_plant.hpp"
#include "plant/two_poster/hydraulic_post.hpp"

namespace rigctl {

struct TwoPosterParams {
  HalfCarParams car;  // the vehicle; its road, speed and active forces are unused here
  std::array<HydraulicPostParams, 2> posts{};
  double substep_s = 1.25e-4;  // [s] RK4 sub-step
};

namespace two_poster_signal {
inline constexpr std::size_t kZr1 = 0, kZr2 = 1, kZu1 = 2, kZu2 = 3, kZs = 4, kPhi = 5;
inline constexpr std::size_t kAs1 = 6, kAs2 = 7;  // body acceleration over each axle [m/s^2]
inline constexpr std::size_t kP1a = 8, kP2a = 9, kP1b = 10, kP2b = 11;  // post 1's p1, p2; post 2's
inline constexpr std::size_t kSimVr1 = 12, kSimVr2 = 13, kSimXs1 = 14, kSimXs2 = 15;
inline constexpr std::size_t kCount = 16;
}  // namespace two_poster_signal

class TwoPosterPlant : public SimulatedPlant {
 public:
  explicit TwoPosterPlant(const TwoPosterParams& params);

  // z_r1, z_r2 (the platens), z_u1, z_u2, z_s, phi, a_s1, a_s2, p1_1, p2_1,
  // p1_2, p2_2, then sim_v_r1, sim_v_r2, sim_x_s1, sim_x_s2.
  const std::vector<ChannelInfo>& signals() const override { return signals_; }
  // u_1, u_2: each post's valve command, fraction of rated, clamped to [-1, 1].
  const std::vector<ChannelInfo>& commands() const override { return commands_; }
  void reset() override;
  void advance(std::span<const double> command, double dt) override;
  void measure(std::span<double> out) const override;

  // Each post's static load [N] and the valve command that holds it at home.
  double static_load(int post) const;
  double rest_command(int post) const;
  const TwoPosterParams& params() const { return params_; }

  // Body z_s, phi, z_u1, z_u2 and rates; posts.
  static constexpr std::size_t kBody = 8;
  struct State {
    std::array<double, kBody> body{};
    std::array<PostState, 2> posts{};
  };
  const State& state() const { return state_; }

 private:
  State derivative(const State& s, const std::array<double, 2>& u) const;
  void rk4(const std::array<double, 2>& u, double h);
  double tyre_force(const State& s, int wheel) const;  // deviation from static, up on the wheel
  std::array<double, 2> corner_forces(const State& s) const;  // on the body, up

  TwoPosterParams params_;
  std::array<double, 2> lever_;  // a, -b
  std::array<double, 2> static_tyre_;  // each tyre's static load [N]
  std::vector<ChannelInfo> signals_, commands_;
  State state_;
};

}  // namespace rigctl

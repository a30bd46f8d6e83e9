// The hidden-effect generator on the two-poster (`rigctl make-run --rig
// two_poster`, tools/hidden_effects/two_poster.cpp): each effect worn into
// the post its cause names, seen in that post's record and hardly in the
// other's. Runs at nominal parameters (--tolerance 0) with one seed, so the
// sensor noise is the same in every run and a difference is the effect's.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "process.hpp"

namespace {

namespace fs = std::filesystem;
using rigctl::test::run_command;

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/half_car_two_poster.yaml";

std::map<std::string, std::vector<double>> read_csv(const std::string& path) {
  std::map<std::string, std::vector<double>> c;
  std::vector<std::string> names;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::vector<std::string> cells;
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    if (names.empty()) {
      names = cells;
      continue;
    }
    for (std::size_t i = 0; i < cells.size() && i < names.size(); ++i) c[names[i]].push_back(std::stod(cells[i]));
  }
  return c;
}

double rms_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s / static_cast<double>(std::min(a.size(), b.size())));
}

class TwoPosterHiddenEffects : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_two_poster_effects_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::map<std::string, std::vector<double>> make_run(const std::string& effect) {
    const std::string out = (dir_ / (effect + ".csv")).string();
    const auto r = run_command(kRigctl + " make-run --rig two_poster --config " + kConfig + " --effect " + effect +
                               " --seed 3 --tolerance 0 --out " + out + " --truth " + out + ".json");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return read_csv(out);
  }
  fs::path dir_;
};

TEST_F(TwoPosterHiddenEffects, EachEffectWearsThePostItNames) {
  const auto clean = make_run("none");
  for (const std::string post : {"1", "2"}) {
    const std::string other = post == "1" ? "2" : "1";
    for (const std::string cause : {"cross_port_leakage_", "actuator_seal_friction_", "entrained_air_"}) {
      SCOPED_TRACE(cause + post);
      const auto worn = make_run(cause + post);
      // The named post's cap pressure moves away from the clean run's; the other post's hardly.
      const double named = rms_difference(worn.at("p1_" + post), clean.at("p1_" + post));
      const double unnamed = rms_difference(worn.at("p1_" + other), clean.at("p1_" + other));
      std::printf("%s%s: p1_%s differs by %.4g Pa rms, p1_%s by %.4g Pa\n", cause.c_str(), post.c_str(), post.c_str(), named,
                  other.c_str(), unnamed);
      EXPECT_GT(named, 3.0 * unnamed);
      EXPECT_GT(named, 1e3);  // [Pa] beyond the transducer's 0.2 bar noise's share: 16-bit steps are 380 Pa
    }
  }
}

TEST_F(TwoPosterHiddenEffects, ACauseWithoutItsPostIsRefusedNamingTheForm) {
  const auto r = run_command(kRigctl + " make-run --rig two_poster --config " + kConfig +
                             " --effect cross_port_leakage --out " + (dir_ / "x.csv").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("causes name their post: cross_port_leakage_1"), std::string::npos) << r.output;
}

}  // namespace

// The matrix FRF file (docs/frf-files.md 2.2) and the plan of a
// multi-channel identification: the file round-trips every entry, its
// errors name the key, each reader names the other format when given it,
// and the shipped two-poster config plans both posts' drives and the
// responses the iteration and its safety check need.
#include <gtest/gtest.h>

#include "config/config_reader.hpp"
#include "tools/identify/frf_file.hpp"
#include "tools/identify/frf_matrix_file.hpp"
#include "tools/identify/mimo_identify.hpp"

namespace rigctl {
namespace {

FrfMatrixData example() {
  FrfMatrixData m;
  m.rig = "two_poster";
  m.config = "rig.yaml";
  m.run_log = "id.lcm";
  m.sample_rate_hz = 400.0;
  m.drives = {{"x_ref_1", "m"}, {"x_ref_2", "m"}};
  m.operating_point = {0.08, 0.07};
  m.responses = {{"z_r1", "m"}, {"u_1", "1"}, {"a_s2", "m/s^2"}};
  m.response_mean = {0.08, -0.01, 0.0};
  m.excitation.band_min_hz = 0.5;
  m.excitation.band_max_hz = 0.7;
  m.excitation.amplitude = {0.006, 0.005};
  m.excitation.realisations = 4;
  m.excitation.period_s = 10.0;
  m.excitation.seed = 7;
  m.excitation.start_s = 9.5;
  m.excitation.end_s = 89.5;
  m.frf.averages = 4;
  for (int k = 0; k < 3; ++k) {
    m.frf.frequency_hz.push_back(0.5 + 0.1 * k);
    Eigen::MatrixXcd h(3, 2);
    Eigen::MatrixXd p(3, 2);
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 2; ++i) {
        h(j, i) = {1.0 + j + 0.1 * i + k, -0.5 * j + i - 0.01 * k};
        p(j, i) = 0.9 - 0.1 * j - 0.2 * i;
      }
    }
    m.frf.value.push_back(h);
    m.frf.partial_coherence.push_back(p);
    m.frf.multiple_coherence.push_back(Eigen::Vector3d(0.99, 0.98 - 0.01 * k, 0.95));
    m.frf.input_condition.push_back(1.0 + 0.1 * k);
  }
  return m;
}

TEST(FrfMatrixFile, RoundTripsEveryEntryCoherenceAndChannel) {
  const FrfMatrixData m = example();
  const FrfMatrixData back = parse_frf_matrix_json(frf_matrix_to_json(m), "m.json");
  ASSERT_EQ(back.drives.size(), 2u);
  EXPECT_EQ(back.drives[1].name, "x_ref_2");
  EXPECT_DOUBLE_EQ(back.operating_point[1], 0.07);
  ASSERT_EQ(back.responses.size(), 3u);
  EXPECT_EQ(back.responses[2].unit, "m/s^2");
  EXPECT_DOUBLE_EQ(back.response_mean[1], -0.01);
  EXPECT_EQ(back.excitation.realisations, 4u);
  EXPECT_DOUBLE_EQ(back.excitation.amplitude[1], 0.005);
  EXPECT_EQ(back.frf.averages, 4);
  ASSERT_EQ(back.frf.frequency_hz.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR((back.frf.value[k] - m.frf.value[k]).norm(), 0.0, 1e-9);
    EXPECT_NEAR((back.frf.partial_coherence[k] - m.frf.partial_coherence[k]).norm(), 0.0, 1e-9);
    EXPECT_NEAR((back.frf.multiple_coherence[k] - m.frf.multiple_coherence[k]).norm(), 0.0, 1e-9);
    EXPECT_NEAR(back.frf.input_condition[k], m.frf.input_condition[k], 1e-9);
  }
}

TEST(FrfMatrixFile, RowsPicksTheAskedResponsesInTheirOrder) {
  const FrfMatrixData m = example();
  const MimoFrf r = m.rows({"a_s2", "z_r1"});
  ASSERT_EQ(r.value[1].rows(), 2);
  EXPECT_EQ(r.value[1](0, 1), m.frf.value[1](2, 1));
  EXPECT_EQ(r.value[1](1, 0), m.frf.value[1](0, 0));
  EXPECT_DOUBLE_EQ(r.multiple_coherence[2](0), 0.95);
  try {
    m.rows({"z_s"});
    FAIL() << "an unknown response was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("z_r1, u_1, a_s2"), std::string::npos) << e.what();
  }
}

TEST(FrfMatrixFile, AMissingEntryIsNamed) {
  std::string text = frf_matrix_to_json(example());
  const auto at = text.find("{\"response\": \"u_1\", \"drive\": \"x_ref_2\"");
  ASSERT_NE(at, std::string::npos);
  const auto end = text.find('}', at);
  text.erase(at, end - at + 3);  // the entry and its ",\n" separator
  try {
    parse_frf_matrix_json(text, "m.json");
    FAIL() << "a matrix without u_1 <- x_ref_2 was read";
  } catch (const FrfFileError& e) {
    EXPECT_NE(std::string(e.what()).find("m.json: matrix: no entry for u_1 from x_ref_2"), std::string::npos) << e.what();
  }
}

TEST(FrfMatrixFile, EachReaderNamesTheOtherFormat) {
  try {
    parse_frf_json(frf_matrix_to_json(example()), "m.json");
    FAIL();
  } catch (const FrfFileError& e) {
    EXPECT_NE(std::string(e.what()).find("a matrix FRF file"), std::string::npos) << e.what();
  }
  try {
    parse_frf_matrix_json("{\"format\": \"rigctl-frf\", \"version\": 1}", "s.json");
    FAIL();
  } catch (const FrfFileError& e) {
    EXPECT_NE(std::string(e.what()).find("a single-channel FRF file"), std::string::npos) << e.what();
  }
}

TEST(MimoIdentifyPlan, TheShippedTwoPosterExcitesBothPostsOnEveryLineOfItsBand) {
  IdentifySettings s;
  s.extra_responses = {"a_s1", "a_s2", "z_r2"};
  const auto plan = plan_mimo_identification(load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/half_car_two_poster.yaml", ""), s);
  EXPECT_EQ(plan.drives, (std::vector<std::string>{"x_ref_1", "x_ref_2"}));
  EXPECT_EQ(plan.responses, (std::vector<std::string>{"z_r1", "z_r2", "u_1", "u_2", "a_s1", "a_s2"}));
  ASSERT_EQ(plan.channels.size(), 2u);
  EXPECT_DOUBLE_EQ(plan.channels[1].operating_point, 0.08);  // mid-stroke of the setpoint range
  EXPECT_EQ(plan.period_ticks, 4000u);                        // 0.1 Hz at 400 Hz
  EXPECT_EQ(plan.lines.size(), 196u);                         // 0.5 .. 20 Hz
  EXPECT_EQ(plan.lines.front(), 5u);
  EXPECT_EQ(plan.realisations, 4u);                           // 80 s of two 10 s periods, and 2 x 2 drives
  // Every trip interlocks the whole rig during the excitation.
  for (const auto& d : plan.config.safety.detectors) EXPECT_EQ(d.action, LimitAction::kInterlock) << d.name;
}

}  // namespace
}  // namespace rigctl

// The energy-peak reading of the paper's Fig. 11 / 13 claim ("rises until about 250 m/s,
// then decreases"), on the absorbed energies of the full `ravel paper` run of 2026-12-02
// (docs/MODEL.md §9; mu = 0.2, charts/fig11_energy_vs_velocity_failure_strain.csv, rounded
// to 0.1 J) and on shapes that must not pass.
#include <gtest/gtest.h>

#include "paper_internal.h"

namespace ravel::studies::paper_detail {
namespace {

Series series(const std::vector<double>& y) {
  Series s;
  for (size_t i = 0; i < y.size(); ++i) s.x.push_back(180 + 20 * double(i)), s.y.push_back(y[i]);
  return s;
}

TEST(PaperClaims, PeakNear250ThenARiseAgainAtHighVelocity) {
  // Failure strain 5.2 %: the peak at 260 m/s falls 18 % by 320 m/s, and 380 m/s is above it.
  const Series s =
      series({50.2, 60.1, 66.8, 73.2, 75.7, 73.9, 65.4, 62.1, 69.2, 74.7, 77.8, 70.1, 68.7, 77.2, 86.2, 74.9, 84.3});
  const EnergyPeak p = find_energy_peak(s);
  ASSERT_EQ(p.peak, 4);
  EXPECT_EQ(s.x[size_t(p.peak)], 260);
  EXPECT_EQ(s.x[size_t(p.trough)], 320);
  EXPECT_NEAR(p.fall, (75.7 - 62.1) / 75.7, 1e-12);
  ASSERT_GE(p.regain, 0);
  EXPECT_EQ(s.x[size_t(p.regain)], 380);
}

TEST(PaperClaims, PeakNear250ThatStaysTheTop) {
  // Failure strain 5.7 %: the peak at 280 m/s, lowest within 60 m/s at 340 (25 % down), never
  // reached again up to 500 m/s.
  const Series s =
      series({55.8, 69.4, 72.9, 79.5, 88.4, 96.5, 76.4, 77.9, 72.8, 82.7, 74.5, 79.9, 88.4, 86.2, 83.3, 79.1, 78.8});
  const EnergyPeak p = find_energy_peak(s);
  ASSERT_EQ(p.peak, 5);
  EXPECT_EQ(s.x[size_t(p.trough)], 340);
  EXPECT_NEAR(p.fall, (96.5 - 72.8) / 96.5, 1e-12);
  EXPECT_EQ(p.regain, -1);
}

TEST(PaperClaims, NoPeakInARisingCurveOrInSmallDips) {
  EXPECT_EQ(find_energy_peak(series({10, 20, 30, 40, 50, 60})).peak, -1);
  // A 10 % dip is scatter, not the paper's drop: the first fall of 15 % is the one found.
  const Series s = series({50, 60, 54, 66, 70, 55, 58});
  const EnergyPeak p = find_energy_peak(s);
  ASSERT_EQ(p.peak, 4);
  EXPECT_EQ(p.trough, 5);
  EXPECT_EQ(p.regain, -1);
  // On a plateau the peak is its first point (the fall within 60 m/s counts from there).
  EXPECT_EQ(find_energy_peak(series({50, 70, 70, 50})).peak, 1);
}

// The mu = 0.02 claim's text (Fig. 17): the broken yarns, and whether they are only the ones
// through the strike point, which no symmetric model can let slip aside.
TEST(PaperClaims, BrokenYarnsThroughTheStrikePointAreNamed) {
  Shot s;
  s.broken_weft_yarns = 1;
  s.broken_weft_lines = {0};
  EXPECT_NE(broken_yarns_text(s).find("only the yarns through the strike point"), std::string::npos);
  EXPECT_EQ(broken_yarns_text(s).rfind("1 weft and 0 warp yarns broken", 0), 0u);
  s.broken_weft_yarns = 3;
  s.broken_weft_lines = {-1, 0, 1};
  EXPECT_EQ(broken_yarns_text(s).find("strike point"), std::string::npos);
  s.broken_weft_yarns = 1;
  s.broken_weft_lines.clear();  // a run kept before the lines were: not known, not claimed
  EXPECT_EQ(broken_yarns_text(s).find("strike point"), std::string::npos);
  s.broken_weft_yarns = 0;
  EXPECT_EQ(broken_yarns_text(s), "0 weft and 0 warp yarns broken");
}

// The friction claim's split at the limit: from the search's lowest perforating run.
TEST(PaperClaims, FrictionAtTheLimitIsTheRunsOwnSplit) {
  Shot s;
  s.velocity_mps = 79.5;
  s.perforated = true;
  s.friction_work_J = 19.56;
  s.friction_work_to_first_break_J = 0.42;
  s.first_break_distance_mm = 59.5;
  EXPECT_EQ(limit_friction_text(s),
            "; at the limit (its lowest perforating run, 79.5 m/s): 0.42 J before the first break (59.5 mm from the "
            "strike point), 19.56 J in all");
  s.first_break_distance_mm = -1;  // no break, or a run kept before the split was
  EXPECT_EQ(limit_friction_text(s), "");
}

}  // namespace
}  // namespace ravel::studies::paper_detail

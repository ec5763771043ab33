#include "core/recon/recon_settings.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace gdvr {
namespace {

TEST(ReconSettingsTest, DefaultsValidateAndPrint) {
  ReconSettings s;
  EXPECT_TRUE(s.validate().ok());
  EXPECT_EQ(s.alpha, 0.2);
  EXPECT_NE(s.to_string().find("method=l2"), std::string::npos);
  EXPECT_NE(s.to_string().find("alpha=0.2"), std::string::npos);
}

TEST(ReconSettingsTest, RejectsAbsurdAlphaNamingTheField) {
  for (double a : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    ReconSettings s;
    s.alpha = a;
    const Status st = s.validate();
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << a;
    EXPECT_NE(st.message().find("alpha"), std::string::npos) << st.message();
  }
}

TEST(ReconSettingsTest, RejectsBadTermWeightsAndCounts) {
  ReconSettings s;
  s.term_weights[term_index(Term::kDt)] = -1;
  EXPECT_NE(s.validate().message().find("term_weights.dt"), std::string::npos);
  s = ReconSettings();
  s.term_weights[0] = 0;
  EXPECT_FALSE(s.validate().ok());
  s = ReconSettings();
  s.l1_inner_iterations = 0;
  EXPECT_NE(s.validate().message().find("l1_inner_iterations"), std::string::npos);
}

TEST(ReconSettingsTest, ParsesMethodNames) {
  for (auto m : {ReconMethod::kNone, ReconMethod::kL2, ReconMethod::kL1, ReconMethod::kUniform,
                 ReconMethod::kWeighted}) {
    auto p = parse_recon_method(recon_method_name(m));
    ASSERT_TRUE(p.ok());
    EXPECT_EQ(p.value(), m);
  }
  EXPECT_FALSE(parse_recon_method("l3").ok());
}

}  // namespace
}  // namespace gdvr

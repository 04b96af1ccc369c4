#include "stereodet/eval/association.h"

#include <gtest/gtest.h>

namespace stereodet {
namespace {

TEST(AssociationTest, OutcomeNamesParseBack) {
  for (Outcome o : {Outcome::kNone, Outcome::kTp, Outcome::kFp, Outcome::kFn, Outcome::kIgnored,
                    Outcome::kDontCare}) {
    EXPECT_EQ(ParseOutcome(OutcomeName(o)), o) << OutcomeName(o);
  }
  EXPECT_STREQ(OutcomeName(Outcome::kDontCare), "dontcare");
  EXPECT_EQ(ParseOutcome("TP"), std::nullopt);  // the records' CSV writes lower case
  EXPECT_EQ(ParseOutcome("tn"), std::nullopt);
}

TEST(AssociationTest, CountsByOutcome) {
  FrameAssociation a;
  a.label_outcome = {Outcome::kTp, Outcome::kFn, Outcome::kTp, Outcome::kIgnored};
  a.det_outcome = {Outcome::kTp, Outcome::kTp, Outcome::kFp, Outcome::kDontCare, Outcome::kNone};
  EXPECT_EQ(a.CountLabels(Outcome::kTp), 2);
  EXPECT_EQ(a.CountLabels(Outcome::kFn), 1);
  EXPECT_EQ(a.CountLabels(Outcome::kFp), 0);
  EXPECT_EQ(a.CountDets(Outcome::kTp), 2);
  EXPECT_EQ(a.CountDets(Outcome::kDontCare), 1);
}

}  // namespace
}  // namespace stereodet

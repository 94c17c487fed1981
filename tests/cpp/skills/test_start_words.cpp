// The --start task's words: blanks split, double quotes keep a value's spaces.
#include <gtest/gtest.h>

#include <stdexcept>

#include "start_words.hpp"

using skillbus::skills::split_start_words;
using Words = std::vector<std::string>;

TEST(StartWords, BlanksSplitAndQuotesKeepSpaces) {
  EXPECT_EQ(split_start_words("ClearTable Gripper=skiros:Gripper-7  Arm=skiros:Arm-8"),
            (Words{"ClearTable", "Gripper=skiros:Gripper-7", "Arm=skiros:Arm-8"}));
  EXPECT_EQ(split_start_words("TaskPlan Goal=\"(skiros:contain skiros:Bin-5 skiros:Cube-2), (skiros:contain a b)\""),
            (Words{"TaskPlan", "Goal=(skiros:contain skiros:Bin-5 skiros:Cube-2), (skiros:contain a b)"}));
  EXPECT_EQ(split_start_words("\"Task Plan\" Text=\"\""), (Words{"Task Plan", "Text="}));
  EXPECT_EQ(split_start_words("  "), Words{});
}

TEST(StartWords, AQuoteLeftOpenIsAnError) {
  EXPECT_THROW(split_start_words("TaskPlan Goal=\"(skiros:contain a b)"), std::runtime_error);
}

// SubmitBudget: what fits, what is refused, and that a refusal is only for now.
#include <optional>
#include <utility>

#include <gtest/gtest.h>

#include "server/api/submit_budget.hpp"

namespace tessera {
namespace {

TEST(SubmitBudgetTest, HoldsWhatFitsAndRefusesTheRest) {
  SubmitBudget budget(100);
  auto first = budget.try_hold(60);
  ASSERT_TRUE(first);
  EXPECT_EQ(budget.held(), 60u);
  EXPECT_FALSE(budget.try_hold(41));  // 101 in all
  auto second = budget.try_hold(40);  // exactly the budget
  ASSERT_TRUE(second);
  EXPECT_EQ(budget.held(), 100u);
  EXPECT_FALSE(budget.try_hold(1));
}

TEST(SubmitBudgetTest, AHoldGivesItsShareBackWhenDone) {
  SubmitBudget budget(100);
  {
    auto hold = budget.try_hold(80);
    ASSERT_TRUE(hold);
    EXPECT_FALSE(budget.try_hold(30));
    // Moved (into a callback, say), it still gives back once.
    std::optional<SubmitBudget::Hold> moved(std::move(*hold));
    hold.reset();
    EXPECT_EQ(budget.held(), 80u);
  }
  EXPECT_EQ(budget.held(), 0u);
  EXPECT_TRUE(budget.try_hold(30));  // the retry gets through
}

TEST(SubmitBudgetTest, MoreThanTheWholeBudgetGoesAlone) {
  SubmitBudget budget(100);
  {
    auto huge = budget.try_hold(1000);
    ASSERT_TRUE(huge);  // nothing else held: refused, it would never get through
    EXPECT_FALSE(budget.try_hold(1));
  }
  auto small = budget.try_hold(1);
  ASSERT_TRUE(small);
  EXPECT_FALSE(budget.try_hold(1000));
  EXPECT_FALSE(budget.try_hold(static_cast<std::size_t>(-1)));  // no overflow
}

}  // namespace
}  // namespace tessera

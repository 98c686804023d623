// SharedText: the ids that millions of tiles name are held once (server/farm/shared_text.hpp).
#include "server/farm/shared_text.hpp"

#include <string>

#include <gtest/gtest.h>

namespace tessera {
namespace {

TEST(SharedTextTest, CopiesHoldTheOneTextAndOutliveTheFirst) {
  SharedText first(std::string("l-0123456789abcdef, longer than a short string"));
  SharedText copy = first;
  EXPECT_EQ(copy.str().data(), first.str().data()) << "a copy took its own characters";
  first.clear();
  EXPECT_TRUE(first.empty());
  EXPECT_EQ(copy, "l-0123456789abcdef, longer than a short string");
}

TEST(SharedTextTest, TheSameTextAssignedAgainKeepsTheOneHeld) {
  const SharedText lease("l-0123456789abcdef");
  SharedText tile = lease;
  const char* held = tile.str().data();
  tile = std::string("l-0123456789abcdef");
  EXPECT_EQ(tile.str().data(), held);
  tile = "l-other";
  EXPECT_NE(tile.str().data(), held);
  EXPECT_EQ(tile, "l-other");
  EXPECT_EQ(lease, "l-0123456789abcdef");
}

TEST(SharedTextTest, EmptyHoldsNothingAndReadsAsTheEmptyString) {
  SharedText text;
  EXPECT_TRUE(text.empty());
  EXPECT_EQ(text.str(), "");
  text = std::string();
  EXPECT_TRUE(text.empty());
  EXPECT_EQ(sizeof(SharedText), sizeof(void*));
  EXPECT_EQ(fmt::format("[{}]", SharedText("w-1")), "[w-1]");
  EXPECT_EQ("lease " + SharedText("l-1"), "lease l-1");
}

}  // namespace
}  // namespace tessera

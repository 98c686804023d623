// printable() and find_control_character(): what may reach a terminal or a log line as it
// is, and what is spelled out.
#include <string>

#include <gtest/gtest.h>

#include "common/printable.hpp"

namespace tessera {
namespace {

TEST(Printable, KeepsTextOfEveryScriptAsItIs) {
  for (const std::string text : {"plain ascii ~!@#", "été", "日本語", "emoji 🎬", "a\\b \"q\""})
    EXPECT_EQ(printable(text), text);
  EXPECT_EQ(find_control_character("été 日本 🎬"), std::string::npos);
}

TEST(Printable, SpellsOutEveryControlCharacter) {
  EXPECT_EQ(printable("a\nb"), "a\\x0ab");
  EXPECT_EQ(printable("a\rb"), "a\\x0db");
  EXPECT_EQ(printable("\x1b[31mred"), "\\x1b[31mred");
  EXPECT_EQ(printable(std::string("nul\0end", 7)), "nul\\x00end");
  EXPECT_EQ(printable("del\x7f"), "del\\x7f");
  EXPECT_EQ(printable("csi\xc2\x9b"), "csi\\xc2\\x9b");  // U+009B, C1
  EXPECT_EQ(printable("nbsp\xc2\xa0"), "nbsp\xc2\xa0");  // U+00A0 is no control
  EXPECT_EQ(find_control_character("ab\x1b"), 2u);
  EXPECT_EQ(find_control_character("é\xc2\x85"), 2u);  // U+0085, NEL
  EXPECT_EQ(find_control_character(std::string("\0", 1)), 0u);
}

TEST(Printable, SpellsOutBytesThatAreNotUtf8) {
  EXPECT_EQ(printable("\xff"), "\\xff");
  EXPECT_EQ(printable("\xc0\xaf"), "\\xc0\\xaf");                    // an overlong '/'
  EXPECT_EQ(printable("\xed\xa0\x80"), "\\xed\\xa0\\x80");           // a surrogate
  EXPECT_EQ(printable("\xe6\x97"), "\\xe6\\x97");                    // cut short
  EXPECT_EQ(printable("\xf4\x90\x80\x80"), "\\xf4\\x90\\x80\\x80");  // above U+10FFFF
  EXPECT_EQ(printable("ok\x80ok"), "ok\\x80ok");
}

}  // namespace
}  // namespace tessera

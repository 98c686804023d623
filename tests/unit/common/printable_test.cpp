// printable() and find_control_character(): what may reach a terminal or a log line as it
// is, and what is spelled out.
#include <string>

#include <gtest/gtest.h>

#include "common/text/printable.hpp"

namespace tessera {
namespace {

TEST(PrintableTest, KeepsTextOfEveryScriptAsItIs) {
  for (const std::string text : {"plain ascii ~!@#", "été", "日本語", "emoji 🎬", "a\\b \"q\""})
    EXPECT_EQ(printable(text), text);
  EXPECT_EQ(find_control_character("été 日本 🎬"), std::string::npos);
}

TEST(PrintableTest, SpellsOutEveryControlCharacter) {
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

TEST(PrintableTest, SpellsOutTheBidirectionalFormattingCharacters) {
  // U+202E RIGHT-TO-LEFT OVERRIDE would show "evil\u202Egnp.exe" as "evilexe.png".
  EXPECT_EQ(printable("evil\xe2\x80\xaegnp.exe"), "evil\\xe2\\x80\\xaegnp.exe");
  for (const char* bidi : {"\xd8\x9c", "\xe2\x80\x8e", "\xe2\x80\x8f", "\xe2\x80\xaa",
                           "\xe2\x80\xab", "\xe2\x80\xac", "\xe2\x80\xad", "\xe2\x80\xae",
                           "\xe2\x81\xa6", "\xe2\x81\xa7", "\xe2\x81\xa8", "\xe2\x81\xa9"}) {
    EXPECT_EQ(find_control_character(std::string("ab") + bidi), 2u) << printable(bidi);
    EXPECT_EQ(control_sequence_at(std::string("ab") + bidi, 2), printable(bidi));
  }
  // Their neighbours are ordinary text: U+2010 (hyphen), U+2065, U+206A and Arabic letters.
  EXPECT_EQ(find_control_character("\xe2\x80\x90\xe2\x81\xa5\xe2\x81\xaa\xd8\xa7"),
            std::string::npos);
}

TEST(PrintableTest, SpellsOutBytesThatAreNotUtf8) {
  EXPECT_EQ(printable("\xff"), "\\xff");
  EXPECT_EQ(printable("\xc0\xaf"), "\\xc0\\xaf");                    // an overlong '/'
  EXPECT_EQ(printable("\xed\xa0\x80"), "\\xed\\xa0\\x80");           // a surrogate
  EXPECT_EQ(printable("\xe6\x97"), "\\xe6\\x97");                    // cut short
  EXPECT_EQ(printable("\xf4\x90\x80\x80"), "\\xf4\\x90\\x80\\x80");  // above U+10FFFF
  EXPECT_EQ(printable("ok\x80ok"), "ok\\x80ok");
}

}  // namespace
}  // namespace tessera

#include "core/util/echo_text.h"

#include <gtest/gtest.h>

namespace gdvr {
namespace {

TEST(EchoTextTest, ShortTextIsKeptWithControlCharsEscaped) {
  EXPECT_EQ(echo_text("cbox/cbox-rgb.xml"), "cbox/cbox-rgb.xml");
  EXPECT_EQ(echo_text(std::string("a\0b\n\x7f", 5)), "a\\x00b\\n\\x7f");
  EXPECT_EQ(escape_control_chars("tab\there"), "tab\\there");
}

TEST(EchoTextTest, LongTextIsCutWithItsLength) {
  std::string out = echo_text(std::string(20000, 'a'));
  EXPECT_EQ(out, std::string(kEchoMaxChars, 'a') + "\xE2\x80\xA6 (20000 characters)");
  EXPECT_EQ(echo_text("abcdef", 3), "abc\xE2\x80\xA6 (6 characters)");
  EXPECT_EQ(echo_text("abc", 3), "abc");
}

TEST(EchoTextTest, NeverSplitsAUtf8Sequence) {
  std::string e_acute = "\xC3\xA9";  // 2 bytes, 1 character
  std::string text;
  for (int i = 0; i < 10; ++i) text += e_acute;
  std::string out = echo_text(text, 4);
  EXPECT_EQ(out, e_acute + e_acute + e_acute + e_acute + "\xE2\x80\xA6 (10 characters)");
}

}  // namespace
}  // namespace gdvr

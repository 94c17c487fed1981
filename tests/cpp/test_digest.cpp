#include <gtest/gtest.h>

#include "skillbus/digest.hpp"

using namespace skillbus;

TEST(Sha256, KnownVector) {
  Sha256 h;
  h.update("abc", 3);
  EXPECT_EQ(to_hex(h.finish()), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Sha256, FinishResetsForTheNextUse) {
  Sha256 h;
  h.update("zzz", 3);
  h.finish();
  h.update("abc", 3);
  EXPECT_EQ(to_hex(h.finish()), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Sha256, StringsAreLengthPrefixedSoBoundariesMatter) {
  Sha256 a, b;
  a.update_str("ab");
  a.update_str("c");
  b.update_str("a");
  b.update_str("bc");
  EXPECT_NE(a.finish(), b.finish());
}

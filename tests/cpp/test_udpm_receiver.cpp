// LcmReassembler: LCM's datagrams into messages (common/src/udpm_receiver.hpp).
#include <gtest/gtest.h>

#include <string>

#include "udpm_receiver.hpp"

using skillbus::LcmReassembler;

namespace {

std::string be32(uint32_t v) { return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }
std::string be16(uint16_t v) { return {char(v >> 8), char(v)}; }
std::string short_msg(const std::string& channel, const std::string& payload) {
  return "LC02" + be32(1) + channel + std::string(1, '\0') + payload;
}
std::string fragment(uint32_t seq, uint32_t size, uint32_t offset, uint16_t no, uint16_t n, const std::string& body) {
  return "LC03" + be32(seq) + be32(size) + be32(offset) + be16(no) + be16(n) + body;
}
bool feed(LcmReassembler& r, const std::string& d, uint64_t sender, LcmReassembler::Message& m) {
  return r.datagram(reinterpret_cast<const uint8_t*>(d.data()), d.size(), sender, m);
}
std::string text(const LcmReassembler::Message& m) { return std::string(reinterpret_cast<const char*>(m.data), m.size); }

}  // namespace

TEST(LcmReassembler, AShortMessageIsItsChannelAndPayload) {
  LcmReassembler r;
  LcmReassembler::Message m;
  const std::string d = short_msg("SB_X", "hello");  // (a short message's bytes are the datagram's)
  ASSERT_TRUE(feed(r, d, 1, m));
  EXPECT_EQ(m.channel, "SB_X");
  EXPECT_EQ(text(m), "hello");
  const std::string empty = short_msg("SB_X", "");
  ASSERT_TRUE(feed(r, empty, 1, m));
  EXPECT_EQ(m.size, 0u);
}

TEST(LcmReassembler, FragmentsInAnyOrderMakeOneMessage) {
  LcmReassembler r;
  LcmReassembler::Message m;
  const std::string first = fragment(9, 9, 0, 0, 3, std::string("SB_Y") + '\0' + "abc");
  EXPECT_FALSE(feed(r, fragment(9, 9, 6, 2, 3, "ghi"), 5, m));
  EXPECT_FALSE(feed(r, first, 5, m));
  EXPECT_FALSE(feed(r, first, 5, m));  // a duplicate changes nothing
  EXPECT_FALSE(feed(r, fragment(4, 3, 0, 0, 2, std::string("SB_Z") + '\0' + "x"), 6, m));  // another sender meanwhile
  ASSERT_TRUE(feed(r, fragment(9, 9, 3, 1, 3, "def"), 5, m));
  EXPECT_EQ(m.channel, "SB_Y");
  EXPECT_EQ(text(m), "abcdefghi");
  ASSERT_TRUE(feed(r, fragment(4, 3, 1, 1, 2, "yz"), 6, m));
  EXPECT_EQ(text(m), "xyz");
  EXPECT_EQ(r.bad, 0);
  EXPECT_EQ(r.incomplete, 0);
}

TEST(LcmReassembler, AMessageThatLostAFragmentIsCountedWhenTheSendersNextBegins) {
  LcmReassembler r;
  LcmReassembler::Message m;
  EXPECT_FALSE(feed(r, fragment(1, 4, 0, 0, 2, std::string("C") + '\0' + "ab"), 3, m));
  EXPECT_FALSE(feed(r, fragment(2, 4, 0, 0, 2, std::string("C") + '\0' + "wx"), 3, m));
  EXPECT_EQ(r.incomplete, 1);
  ASSERT_TRUE(feed(r, fragment(2, 4, 2, 1, 2, "yz"), 3, m));
  EXPECT_EQ(text(m), "wxyz");
}

TEST(LcmReassembler, WhatDoesNotParseIsCountedNeverDelivered) {
  LcmReassembler r;
  LcmReassembler::Message m;
  const std::string bad[] = {
      "", "LC0", "LC02", "LC02" + be32(0) + "NO_NUL", "LC02" + be32(0) + std::string(1, '\0') + "no channel",
      "LC02" + be32(0) + std::string(64, 'A') + std::string(1, '\0'),  // a channel of 64 bytes (63 at most)
      "XXXX" + std::string(30, 'x'),
      fragment(1, 10, 0, 0, 0, "C"),                        // no fragments
      fragment(1, 10, 0, 2, 2, "x"),                        // fragment 2 of 2
      fragment(1, 4, 2, 1, 2, "xyz"),                       // past the end
      fragment(1, 1u << 30, 0, 0, 2, std::string("C") + '\0'),  // a gigabyte
  };
  for (const auto& d : bad) EXPECT_FALSE(feed(r, d, 1, m)) << d;
  EXPECT_EQ(r.bad, static_cast<long>(std::size(bad)));
}

// The kernel filter of a udpm:// socket (skillbus/channel_filter.hpp), on a real UDP
// socket: datagrams sent to it over loopback unicast pass the same socket filter the
// kernel runs for multicast ones.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "skillbus/channel_filter.hpp"

namespace {

std::string short_msg(const std::string& channel, const std::string& payload = "x") {
  return std::string("LC02") + std::string("\0\0\0\1", 4) + channel + std::string(1, '\0') + payload;
}

// A receiving socket on 127.0.0.1 and a sender aimed at it.
class Sockets {
 public:
  Sockets() {
    rx = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK, 0);
    tx = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::bind(rx, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
    socklen_t n = sizeof(to);
    ::getsockname(rx, reinterpret_cast<sockaddr*>(&to), &n);
  }
  ~Sockets() {
    ::close(rx);
    ::close(tx);
  }
  void send(const std::string& d) {
    ASSERT_EQ(::sendto(tx, d.data(), d.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to)),
              static_cast<ssize_t>(d.size()));
  }
  // Everything queued on the receiving socket, in order (loopback delivers as it sends).
  std::vector<std::string> queued() {
    std::vector<std::string> out;
    char buf[70000];
    for (ssize_t n; (n = ::recv(rx, buf, sizeof(buf), 0)) >= 0;) out.emplace_back(buf, static_cast<size_t>(n));
    return out;
  }
  int rx = -1, tx = -1;
  sockaddr_in to{};
};

}  // namespace

TEST(ChannelFilter, KeepsTheSubscribedChannelsAndWhateverIsNoShortMessage) {
  Sockets s;
  std::string why;
  // Names whose bytes with the NUL end on each remainder of 4 (the filter compares by
  // words, then a half word and a byte).
  ASSERT_TRUE(skillbus::attach_channel_filter(s.rx, {"SB_A", "SB_AB", "SB_ABC", "SB_ABCDEFG", "SB_ABCDEFGH"}, why))
      << why;
  const std::string fragment = std::string("LC03") + std::string(16, '\1') + "SB_OTHER";
  const std::vector<std::string> sent = {
      short_msg("SB_A"),         short_msg("SB_B"),   short_msg("SB_AB"),     short_msg("SB_A_LONGER"),
      short_msg("SB_"),          short_msg("SB_ABC"), short_msg("SB_ABCDEF"), short_msg("SB_ABCDEFG"),
      short_msg("SB_ABCDEFGH"),  short_msg("SB_ABCDEFGH", ""), fragment,  "not lcm at all",
      "LC0",
      // Malformed short messages, kept for the reader to count: cut short before the
      // NUL, an empty channel, a channel over LCM's 63 characters.
      std::string("LC02\0\0\0\1SB_B", 12), short_msg(""), short_msg(std::string(64, 'C')),
      short_msg(std::string(63, 'C')),  // (the longest a channel can be: another's, dropped)
  };
  for (const auto& d : sent) s.send(d);
  const std::vector<std::string> kept = {
      short_msg("SB_A"), short_msg("SB_AB"), short_msg("SB_ABC"), short_msg("SB_ABCDEFG"), short_msg("SB_ABCDEFGH"),
      short_msg("SB_ABCDEFGH", ""), fragment, "not lcm at all", "LC0",
      std::string("LC02\0\0\0\1SB_B", 12), short_msg(""), short_msg(std::string(64, 'C'))};
  EXPECT_EQ(s.queued(), kept);
}

TEST(ChannelFilter, IsReplacedWithTheSubscriptionsAndCanBeRemoved) {
  Sockets s;
  std::string why;
  ASSERT_TRUE(skillbus::attach_channel_filter(s.rx, {"SB_A"}, why));
  ASSERT_TRUE(skillbus::attach_channel_filter(s.rx, {"SB_B"}, why));
  s.send(short_msg("SB_A"));
  s.send(short_msg("SB_B"));
  EXPECT_EQ(s.queued(), std::vector<std::string>{short_msg("SB_B")});
  ASSERT_TRUE(skillbus::attach_channel_filter(s.rx, {}, why));  // nothing subscribed: no short message
  s.send(short_msg("SB_B"));
  EXPECT_TRUE(s.queued().empty());
  skillbus::detach_channel_filter(s.rx);
  s.send(short_msg("SB_A"));
  EXPECT_EQ(s.queued(), std::vector<std::string>{short_msg("SB_A")});
}

TEST(ChannelFilter, TooManyChannelsForOneProgramLeaveTheSocketUnfilteredAndSayWhy) {
  Sockets s;
  std::string why;
  ASSERT_TRUE(skillbus::attach_channel_filter(s.rx, {"SB_A"}, why));
  std::vector<std::string> many;
  for (int i = 0; i < 400; ++i) many.push_back("SB_A_CHANNEL_WITH_A_LONG_NAME_" + std::to_string(i));
  EXPECT_FALSE(skillbus::attach_channel_filter(s.rx, many, why));
  EXPECT_NE(why.find("instructions"), std::string::npos) << why;
  s.send(short_msg("SB_B"));  // (the old filter is gone too: every datagram is the reader's)
  EXPECT_EQ(s.queued(), std::vector<std::string>{short_msg("SB_B")});
}

// Local by default (skillbus/bus.hpp, check_multicast_interface): a udpm:// bus joins its
// multicast group on the interface the routing table picks for the group. On a host whose
// default route goes out of a real network card that is that card: the process then hears
// (and, with ttl>0, talks to) the whole network. skillbus refuses that unless the network
// was chosen ($SKILLBUS_NETWORK, `--network IFACE`).
#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <regex>

#include "skillbus/bus.hpp"

namespace skillbus {

namespace {

// The interface that holds `addr` ("" if none does).
std::string interface_of(in_addr addr) {
  ifaddrs* all = nullptr;
  if (::getifaddrs(&all) != 0) return "";
  std::string name;
  for (ifaddrs* i = all; i; i = i->ifa_next)
    if (i->ifa_addr && i->ifa_addr->sa_family == AF_INET &&
        reinterpret_cast<sockaddr_in*>(i->ifa_addr)->sin_addr.s_addr == addr.s_addr) {
      name = i->ifa_name;
      break;
    }
  ::freeifaddrs(all);
  return name;
}

}  // namespace

void check_multicast_interface(const std::string& url) {
  static const std::regex udpm(R"(^udpm://([0-9.]*)(?::(\d+))?)");
  std::smatch m;
  if (!std::regex_search(url, m, udpm)) return;
  const std::string group = m[1].str().empty() ? "239.255.76.67" : m[1].str();
  const int port = m[2].matched ? std::stoi(m[2].str()) : 7667;
  // Where would a datagram to the group leave from? (connect() on UDP sends nothing.)
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return;
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<uint16_t>(port));
  if (::inet_pton(AF_INET, group.c_str(), &to.sin_addr) != 1) {
    ::close(fd);
    return;  // LCM names the bad URL itself
  }
  sockaddr_in from{};
  socklen_t len = sizeof(from);
  const bool routed = ::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof(to)) == 0 &&
                      ::getsockname(fd, reinterpret_cast<sockaddr*>(&from), &len) == 0;
  ::close(fd);
  if (!routed) return;  // no route: LCM fails with its own message
  if ((ntohl(from.sin_addr.s_addr) >> 24) == 127) return;  // loopback: this host only
  const std::string iface = interface_of(from.sin_addr);
  const char* allowed = std::getenv("SKILLBUS_NETWORK");
  if (allowed && *allowed && iface == allowed) return;
  char ip[INET_ADDRSTRLEN] = "?";
  ::inet_ntop(AF_INET, &from.sin_addr, ip, sizeof(ip));
  throw BusError("bus URL '" + url + "': the multicast group " + group + " would be joined on the network interface " +
                 (iface.empty() ? std::string("?") : iface) + " (" + ip +
                 "), where other hosts can reach it. skillbus stays on this host unless told otherwise: run "
                 "inside a private network namespace (deploy/netns-run ...), or route multicast to loopback "
                 "(sudo ip route add 224.0.0.0/4 dev lo), or allow that network with --network " +
                 (iface.empty() ? std::string("IFACE") : iface) + " (or SKILLBUS_NETWORK=" +
                 (iface.empty() ? std::string("IFACE") : iface) + "; docs/security.md)");
}

}  // namespace skillbus

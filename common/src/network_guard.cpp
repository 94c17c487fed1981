// Local by default (skillbus/bus.hpp, check_multicast_interface): a udpm:// bus joins its
// multicast group on the interface the routing table picks for the group. On a host whose
// default route goes out of a real network card that is that card: the process then hears
// (and, with ttl>0, talks to) the whole network. skillbus refuses that unless the network
// was chosen ($SKILLBUS_NETWORK, `--network IFACE`). The same rule as the Python bus
// (skillbus.bus.check_multicast_interface): the main table's longest matching route, read
// from /proc/net/route.
#include <arpa/inet.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "skillbus/bus.hpp"

namespace skillbus {

namespace {

uint32_t le_hex(const std::string& hex) {  // /proc/net/route writes addresses little-endian
  const uint32_t v = static_cast<uint32_t>(std::stoul(hex, nullptr, 16));
  return ((v & 0xff) << 24) | ((v & 0xff00) << 8) | ((v >> 8) & 0xff00) | (v >> 24);
}

// The interface of the longest matching route for `address` (host order), "" if none.
std::string route_interface(uint32_t address) {
  std::ifstream table("/proc/net/route");
  std::string line, best;
  int best_len = -1;
  long best_metric = 0;
  std::getline(table, line);  // the header
  while (std::getline(table, line)) {
    std::istringstream f(line);
    std::string iface, dest, gateway, flags, refcnt, use, metric, mask;
    if (!(f >> iface >> dest >> gateway >> flags >> refcnt >> use >> metric >> mask)) continue;
    try {
      if (!(std::stoul(flags, nullptr, 16) & 1)) continue;  // RTF_UP
      const uint32_t d = le_hex(dest), m = le_hex(mask);
      const int len = __builtin_popcount(m);
      const long met = std::stol(metric);
      if ((address & m) == (d & m) && (len > best_len || (len == best_len && met < best_metric)))
        best = iface, best_len = len, best_metric = met;
    } catch (const std::exception&) {
      continue;
    }
  }
  return best;
}

}  // namespace

void check_multicast_interface(const std::string& url) {
  static const std::regex udpm(R"(^udpm://([0-9.]*))");
  std::smatch m;
  if (!std::regex_search(url, m, udpm)) return;
  const std::string group = m[1].str().empty() ? "239.255.76.67" : m[1].str();
  in_addr a{};
  if (::inet_pton(AF_INET, group.c_str(), &a) != 1) return;  // LCM names the bad URL itself
  const std::string iface = route_interface(ntohl(a.s_addr));
  const char* allowed = std::getenv("SKILLBUS_NETWORK");
  if (iface.empty() || iface == "lo" || (allowed && iface == allowed)) return;  // (no route: LCM says so)
  throw BusError("bus URL '" + url + "': the multicast group " + group + " would be joined on the network interface " +
                 iface +
                 ", where other hosts can reach it. skillbus stays on this host unless told otherwise: run inside a "
                 "private network namespace (deploy/netns-run ...), or route multicast to loopback (sudo ip route add "
                 "224.0.0.0/4 dev lo), or allow that network with --network " +
                 iface + " (or SKILLBUS_NETWORK=" + iface + "; docs/security.md)");
}

}  // namespace skillbus

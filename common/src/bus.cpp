// open_bus(): picks the backend by URL scheme: LCM (udpm://, memq://, file://) or Cyclone
// DDS (dds://), behind the deployment's key either way.
#include <cstdlib>

#include "dds_bus.hpp"
#include "lcm_bus.hpp"
#include "skillbus/auth.hpp"
#include "skillbus/bus.hpp"

namespace skillbus {

std::string resolve_bus_url(const std::string& url) {
  if (!url.empty()) return url;
  const char* env = std::getenv("SKILLBUS_BUS_URL");
  if (env && *env) return env;
  return kDefaultBusUrl;
}

std::unique_ptr<Bus> open_bus(const std::string& url_in) {
  const std::string url = resolve_bus_url(url_in);
  const auto scheme_end = url.find("://");
  const std::string scheme = scheme_end == std::string::npos ? "" : url.substr(0, scheme_end);
  if (scheme == "udpm") check_multicast_interface(url);
  if (scheme == "udpm" || scheme == "memq" || scheme == "file" || scheme == "tcpq")
    return auth::authenticated(std::make_unique<LcmBus>(url));
  if (scheme == "dds") return auth::authenticated(std::make_unique<DdsBus>(url));
  throw BusError("bus URL '" + url + "': unknown scheme (expected udpm://, memq:// or dds://)");
}


}  // namespace skillbus

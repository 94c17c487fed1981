// One auth::Opener shared by the bus's Python side (skillbus_native.Opener) and the
// quiet-frame core (QuietFrames): one replay window per sender, whichever of the two
// verifies a message, so a message either has accepted is a replay to the other.
#pragma once

#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "skillbus/auth.hpp"

namespace skillbus::native {

struct SharedOpener {
  SharedOpener(std::vector<auth::Key> keys, std::shared_ptr<const auth::Policy> policy)
      : opener(std::move(keys), std::move(policy)) {}
  auth::Opener opener;
  std::mutex mutex;  // QuietFrames verifies without the GIL, Python with it
};

}  // namespace skillbus::native

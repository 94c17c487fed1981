// Durability: an append-only journal of committed transactions and periodic snapshots
// in a data directory. A transaction's record is on disk (fdatasync) before the server
// acknowledges it; after a crash, recover() returns the last snapshot and every record
// after it. A record torn by the crash (short, or failing its CRC) ends the journal:
// it was never acknowledged, and is cut off.
//
// Files: snapshot.bin (wm_snapshot_t), journal.bin (records: u32 length, u32 CRC-32 of
// the bytes, the bytes of a wm_txn_t whose expected_version is the version it was
// applied to). A new snapshot is written beside, synced, renamed over the old one, and
// then the journal starts afresh.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "skillbus_msgs/wm_snapshot_t.hpp"
#include "skillbus_msgs/wm_txn_t.hpp"

namespace skillbus::wm {

class Journal {
 public:
  explicit Journal(std::string dir);  // creates the directory; throws WmError if it cannot
  ~Journal();

  struct Recovered {
    std::optional<skillbus_msgs::wm_snapshot_t> snapshot;
    std::vector<skillbus_msgs::wm_txn_t> txns;  // in commit order
    std::string note;                           // e.g. a cut-off torn record
  };
  Recovered recover();  // call once, before append

  void append(const skillbus_msgs::wm_txn_t& txn);  // durable on return; throws WmError
  void write_snapshot(const skillbus_msgs::wm_snapshot_t& snapshot);
  long records_since_snapshot() const { return records_; }
  const std::string& dir() const { return dir_; }

 private:
  void open_journal(bool truncate);
  std::string dir_;
  int fd_ = -1;
  long records_ = 0;
};

}  // namespace skillbus::wm

// Durability: an append-only journal of committed transactions and snapshots in a data
// directory. A transaction's record is on disk (fdatasync) before the server acknowledges
// it; recover() returns the last snapshot and every record after it.
//
// Files (little-endian; CRC is zlib's CRC-32):
//   snapshot.bin  "SBWMSNP1", u32 length, u32 CRC of the body, body (wm_snapshot_t).
//                 Written beside, synced, renamed, the directory synced: never torn.
//   journal.bin   header: "SBWMJNL1", i64 base version (the snapshot's version it goes on
//                 from; 0 without a snapshot), u32 CRC of those 16 bytes. Written the same
//                 way at a snapshot (and in a new data directory), so it always exists
//                 next to a snapshot. Then records, each
//                   frame  u32 length, u32 CRC of the body, u32 CRC of those 8 bytes
//                   body   a wm_txn_t whose expected_version is the version it applied to
//                          (record i of a journal applied to base + i)
//                   frame  the same 12 bytes again
//   lock          flock()ed by the process that uses the directory.
//
// Reading the journal tells a torn tail from corruption:
//   torn     a partial record at the very end, after the last complete record: a frame
//            cut short, a record running past the end of the file, zeros to the end, or a
//            record whose body fails its CRC and whose closing frame is missing, with no
//            valid record after it. A crash during an unacknowledged write leaves that;
//            recover() cuts it off and logs a warning with its offset.
//   corrupt  anything else: a record that fails its CRC although it was completely
//            written (its closing frame is there) or has valid records after it, a
//            damaged frame with data after it, a body that does not decode, a record out
//            of version order, a damaged header. recover() throws DataError naming the
//            file, the byte offset and the records affected, and changes nothing;
//            repair_data_dir() keeps the intact records before the damage.
// A missing file is an error when the other one says it should be there: a snapshot
// without a journal (the commits after the snapshot would be lost), a journal that goes
// on from a snapshot that is not there. Neither file: a new data directory.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "skillbus/wm/model.hpp"
#include "skillbus_msgs/wm_snapshot_t.hpp"
#include "skillbus_msgs/wm_txn_t.hpp"

namespace skillbus::wm {

// The data directory cannot be used as it is without losing acknowledged commits: a
// damaged or missing file. The message (one line) names the file and what to do; the
// files are left as they were.
class DataError : public WmError {
 public:
  using WmError::WmError;
};

namespace journal_format {
constexpr size_t kHeaderSize = 20;  // magic, i64 base version, CRC
constexpr size_t kFrameSize = 12;   // u32 length, u32 body CRC, u32 CRC of the 8 bytes
constexpr size_t kRecordOverhead = 2 * kFrameSize;
constexpr uint32_t kMaxBody = 1u << 30;  // a longer body is impossible
constexpr size_t kSnapshotHeaderSize = 16;
}  // namespace journal_format

// What a journal file holds, read without changing it.
struct JournalScan {
  enum class End { Clean, Torn, Corrupt };
  bool header_ok = false;
  int64_t base_version = 0;
  std::vector<uint64_t> offsets;                // of each intact record, in order
  std::vector<skillbus_msgs::wm_txn_t> txns;    // the intact records before any damage
  uint64_t good_end = 0;                        // where the last intact record ends
  uint64_t size = 0;                            // the file's size
  End end = End::Clean;
  std::string why;                              // Torn/Corrupt: what is wrong at good_end
  // Corrupt: the intact records found after the damage (they cannot be applied without
  // the damaged one) and the versions they would have made.
  long intact_after = 0;
  int64_t after_first_version = 0, after_last_version = 0;
};
JournalScan scan_journal(const std::string& path);  // throws WmError if it cannot read

class Journal {
 public:
  // Creates the directory if needed and locks it (DIR/lock); throws WmError if it cannot
  // or another process holds it.
  explicit Journal(std::string dir);
  ~Journal();
  Journal(const Journal&) = delete;
  Journal& operator=(const Journal&) = delete;

  struct Recovered {
    std::optional<skillbus_msgs::wm_snapshot_t> snapshot;
    std::vector<skillbus_msgs::wm_txn_t> txns;  // after the snapshot, in commit order
    std::string note;                           // e.g. a cut-off torn record, a new directory
  };
  // Call once, before append. Throws DataError (files untouched) when the directory is
  // damaged; cuts a torn tail; makes what it returns durable before returning.
  Recovered recover();

  void append(const skillbus_msgs::wm_txn_t& txn);  // durable on return; throws WmError
  // A new snapshot, then a new empty journal going on from its version.
  void write_snapshot(const skillbus_msgs::wm_snapshot_t& snapshot);
  long records_since_snapshot() const { return records_; }
  const std::string& dir() const { return dir_; }

 private:
  void start_journal(int64_t base_version);
  std::string dir_;
  int lock_fd_ = -1;
  int fd_ = -1;
  uint64_t size_ = 0;    // the journal's length: its last complete record's end
  long records_ = 0;
  std::string broken_;   // why appends are refused (a write whose durability is unknown)
};

// `wm_server --repair`: checks a data directory; when its journal is damaged, writes the
// intact records before the damage as a new journal.bin and keeps the original as
// journal.bin.corrupt (or .corrupt.N); a missing journal next to a snapshot becomes an
// empty one after it. exit_code 0: repaired, or nothing to repair; 1: cannot repair
// (the message says why and what a person can do). `message` is one line per finding.
struct RepairResult {
  int exit_code = 0;
  std::string message;
};
RepairResult repair_data_dir(const std::string& dir);

}  // namespace skillbus::wm

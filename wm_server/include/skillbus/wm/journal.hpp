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
//   scene_imports.V.ttl, scene_extra.V.ttl
//                 the scene's triples that are no elements, per world version V of a scene
//                 change (Journal::write_scene_files).
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
//
// Snapshots in the background (start_snapshot): the server hands over an image of the
// world (WorldImage: pointers to immutable elements, taken in a few milliseconds) and a
// thread encodes and writes snapshot.bin.tmp piece by piece, syncs and renames it, while
// commits go on being appended to the old journal. A snapshot at version V next to a
// journal going on from an older version is a consistent directory already (recovery
// skips the records the snapshot has), so nothing waits for the snapshot. Then the
// thread writes the new journal: its header (base V) and a copy of the old journal's
// records after V, synced; only the last step holds the appends back: the records
// appended meanwhile copied too, the rename, the directory's sync. A crash at any point
// leaves either the old pair or the new one, each with every acknowledged record.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "skillbus/wm/model.hpp"
#include "skillbus/wm/store.hpp"
#include "skillbus_msgs/wm_commit_t.hpp"
#include "skillbus_msgs/wm_element_t.hpp"
#include "skillbus_msgs/wm_relation_t.hpp"
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

// What a snapshot holds, as the server hands it to the journal: the world (an image,
// cheap to take) and the remembered commits (exactly-once across restarts).
struct SnapshotData {
  WorldImage world;
  std::vector<skillbus_msgs::wm_commit_t> recent;
};

// A snapshot file, checked (length, CRC, fingerprint) but decoded one element at a time,
// so that a large world is never held twice (as messages and as the store). The file's
// bytes are mapped, not copied, while it lives.
class SnapshotFile {
 public:
  explicit SnapshotFile(const std::string& path);  // throws DataError (damaged), WmError (cannot read)
  ~SnapshotFile();
  SnapshotFile(const SnapshotFile&) = delete;
  SnapshotFile& operator=(const SnapshotFile&) = delete;
  int64_t version() const { return version_; }
  int64_t next_id() const { return next_id_; }
  int64_t total() const { return num_elements_; }
  // Each calls fn once per item, in file order; throw DataError if the bytes do not
  // decode (they passed the CRC: a writer's bug, not a crash).
  void for_each_element(const std::function<void(skillbus_msgs::wm_element_t&)>& fn) const;
  void for_each_relation(const std::function<void(skillbus_msgs::wm_relation_t&)>& fn) const;
  std::vector<skillbus_msgs::wm_commit_t> recent() const;
  // The whole snapshot as one message (tests and small worlds).
  skillbus_msgs::wm_snapshot_t decode_all() const;

 private:
  [[noreturn]] void undecodable(const std::string& what) const;
  std::string path_;
  const uint8_t* body_ = nullptr;  // after the 16-byte file header
  size_t size_ = 0;                // of the body
  void* map_ = nullptr;
  size_t map_size_ = 0;
  int64_t version_ = 0, next_id_ = 0;
  int32_t num_elements_ = 0;
  size_t elements_at_ = 0;  // offsets in the body, found by one pass at open
  size_t relations_at_ = 0;
  size_t recent_at_ = 0;
  int32_t num_relations_ = 0, num_recent_ = 0;
};

class Journal {
 public:
  // Creates the directory if needed and locks it (DIR/lock); throws WmError if it cannot
  // or another process holds it.
  explicit Journal(std::string dir);
  ~Journal();
  Journal(const Journal&) = delete;
  Journal& operator=(const Journal&) = delete;

  struct Recovered {
    std::shared_ptr<SnapshotFile> snapshot;     // none in a new data directory
    std::vector<skillbus_msgs::wm_txn_t> txns;  // after the snapshot, in commit order
    std::string note;                           // e.g. a cut-off torn record, a new directory
  };
  // Call once, before append. Throws DataError (files untouched) when the directory is
  // damaged; cuts a torn tail; makes what it returns durable before returning.
  Recovered recover();

  void append(const skillbus_msgs::wm_txn_t& txn);  // durable on return; throws WmError
  // A new snapshot, then a new empty journal going on from its version; durable on
  // return (a scene load: the world it replaces is in no journal). Waits for a
  // background snapshot first.
  void write_snapshot(const SnapshotData& snapshot);
  void write_snapshot(const skillbus_msgs::wm_snapshot_t& snapshot);
  // Starts writing a snapshot of `snapshot.world.version` (the version of the last
  // appended record) in the background and returns at once; false (nothing started)
  // while one is still being written. Its failure is logged and leaves the old snapshot
  // and journal, which stay consistent; the next one is tried `retry_after` records on.
  bool start_snapshot(SnapshotData snapshot);
  bool snapshot_running() const;
  void wait_for_snapshot();  // until the background snapshot, if any, has ended
  // From now on every append and snapshot is refused with `why` (the data directory no
  // longer matches what the server holds): nothing more is acknowledged until a restart.
  void fail(const std::string& why);
  // Records in the journal after the snapshot, and whether a snapshot is due (`every`
  // records since the last one, or since the last attempt that failed).
  long records_since_snapshot() const;
  bool snapshot_due(long every) const;
  long snapshots_written() const;
  // Tests: called by the background thread between its steps ("written": the snapshot
  // file is complete, before its sync; "renamed"; "journal": the new journal is written,
  // before the appends are held back), to hold it there or to crash there.
  std::function<void(const char* step)> test_hook;
  const std::string& dir() const { return dir_; }
  // The loaded scene's triples that are no elements (Scene::extra) and the ontologies it
  // imported from the server's library (the library's files may change or go; the world
  // keeps the concepts it was loaded with), as Turtle. A scene load or new axioms take the
  // world to a new version V with new ones: a generation of two files,
  // DIR/scene_imports.V.ttl and DIR/scene_extra.V.ttl, written durably before the snapshot
  // of V. The generation in force is the newest that is not newer than the snapshot, so a
  // crash between the files and the snapshot leaves the old scene whole. (Files without a
  // version, DIR/scene_imports.ttl and DIR/scene_extra.ttl, are the generation of version 0.)
  struct SceneFiles {
    int64_t version = 0;  // of the generation; 0 when there is none
    std::string imports, extra;
    std::string imports_path, extra_path;  // to name in errors
  };
  void write_scene_files(int64_t version, const std::string& imports, const std::string& extra);
  // The generation in force next to a snapshot at `snapshot_version` (0 without one).
  // Removes, durably, the generations that never got their snapshot and those it replaced.
  SceneFiles settle_scene_files(int64_t snapshot_version);
  // Removes the generation of `version` (a change that could not be made durable); throws
  // WmError if it cannot: a later snapshot at that version would take it for its own.
  void remove_scene_files(int64_t version);

 private:
  void start_journal(int64_t base_version);
  void write_snapshot_file(const SnapshotData& snapshot) const;
  void rotate_journal(int64_t base_version, uint64_t tail_from, long records_before);
  void background(SnapshotData snapshot, uint64_t tail_from, long records_before);
  void join_finished();
  std::string dir_;
  int lock_fd_ = -1;
  // Appends and the switch to a new journal exclude each other; the snapshot file itself
  // is written without the lock.
  mutable std::mutex mu_;
  std::condition_variable done_cv_;
  int fd_ = -1;
  uint64_t size_ = 0;    // the journal's length: its last complete record's end
  long records_ = 0;
  long attempt_at_ = 0;  // records_ when the last snapshot was started and failed
  long snapshots_ = 0;
  bool running_ = false;
  std::thread worker_;
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

// Writes DIR/NAME so that it is either the old file or the whole new one, on disk on
// return (beside as NAME.tmp, synced, renamed, the directory synced); WmError naming why.
void write_file_durably(const std::string& dir, const std::string& name, const std::string& bytes);

}  // namespace skillbus::wm

// The journal: records recovered in order; a torn tail (what a crash during an
// unacknowledged write leaves) cut off; corruption anywhere else refused with the file,
// offset and records named, the files left byte for byte as they were; missing files;
// the repair that keeps the intact prefix.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>

#include "skillbus/wm/convert.hpp"
#include "skillbus/wm/journal.hpp"
#include "skillbus/wm/model.hpp"
#include "wm_test_util.hpp"

using namespace skillbus::wm;
namespace fs = std::filesystem;
namespace jf = skillbus::wm::journal_format;

namespace {

struct TempDir {
  fs::path path = fs::temp_directory_path() / ("wm-journal-" + std::to_string(::getpid()) + "-" +
                                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
  TempDir() { fs::remove_all(path); }
  ~TempDir() { fs::remove_all(path); }
  std::string journal() const { return (path / "journal.bin").string(); }
  std::string snapshot() const { return (path / "snapshot.bin").string(); }
};

skillbus_msgs::wm_txn_t txn(int64_t version, const std::string& label) {
  skillbus_msgs::wm_txn_t t{};
  t.client_id = "c";
  t.request_id = version + 1;
  t.expected_version = version;
  skillbus_msgs::wm_op_t op{};
  op.kind = skillbus_msgs::wm_op_t::ADD_ELEMENT;
  op.element.type = "skiros:Cube";
  op.element.label = label;
  t.ops = {op};
  t.num_ops = 1;
  return t;
}

std::string read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << bytes;
}

// A data directory whose journal holds n records after version `base` (a snapshot at
// `base` when base > 0), labels r<version>.
void make_dir(const TempDir& d, int n, int64_t base = 0) {
  Journal j(d.path.string());
  j.recover();
  if (base > 0) {
    skillbus_msgs::wm_snapshot_t s{};
    s.world.version = base;
    j.write_snapshot(s);
  }
  for (int i = 0; i < n; ++i) j.append(txn(base + i, "r" + std::to_string(base + i)));
}

size_t recovered_count(const TempDir& d) {
  Journal j(d.path.string());
  return j.recover().txns.size();
}

// recover() throws DataError; returns its message.
std::string refusal(const TempDir& d) {
  Journal j(d.path.string());
  try {
    j.recover();
  } catch (const DataError& e) {
    return e.what();
  }
  ADD_FAILURE() << "recover() accepted a damaged data directory";
  return "";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST(Journal, RecoversEveryAppendedRecordInOrder) {
  TempDir d;
  make_dir(d, 50);
  Journal j(d.path.string());
  auto rec = j.recover();
  ASSERT_EQ(rec.txns.size(), 50u);
  EXPECT_EQ(rec.txns[49].ops[0].element.label, "r49");
  EXPECT_TRUE(rec.note.empty());
  const JournalScan s = scan_journal(d.journal());
  EXPECT_EQ(s.offsets.front(), jf::kHeaderSize);
  EXPECT_EQ(s.good_end, s.size);
  EXPECT_EQ(s.end, JournalScan::End::Clean);
}

TEST(Journal, ANewDataDirectoryGetsAnEmptyJournalAtVersion0) {
  TempDir d;
  {
    Journal j(d.path.string());
    auto rec = j.recover();
    EXPECT_FALSE(rec.snapshot);
    EXPECT_TRUE(rec.txns.empty());
  }
  EXPECT_TRUE(fs::exists(d.journal()));
  EXPECT_EQ(scan_journal(d.journal()).base_version, 0);
  EXPECT_EQ(recovered_count(d), 0u);
}

TEST(Journal, ATornLastRecordIsCutOffAndTheRestKept) {
  TempDir d;
  make_dir(d, 3);
  const auto size = fs::file_size(d.journal());
  fs::resize_file(d.journal(), size - 5);  // a crash in the middle of the last write
  {
    Journal j(d.path.string());
    auto rec = j.recover();
    EXPECT_EQ(rec.txns.size(), 2u);
    EXPECT_TRUE(contains(rec.note, "torn")) << rec.note;
    EXPECT_TRUE(contains(rec.note, "at byte " + std::to_string(scan_journal(d.journal()).good_end))) << rec.note;
    j.append(txn(2, "again"));  // appends after the cut, not after the garbage
  }
  Journal j(d.path.string());
  auto rec = j.recover();
  ASSERT_EQ(rec.txns.size(), 3u);
  EXPECT_EQ(rec.txns[2].ops[0].element.label, "again");
}

// Every length a crash can leave (the file's prefix at any byte: a power loss keeps a
// prefix of what was written after the last sync) recovers the records complete in it,
// never refuses; zeros where the unsynced record should be are a torn tail too.
TEST(Journal, EveryPrefixOfTheFileRecoversItsCompleteRecordsAndNeverRefuses) {
  TempDir d;
  make_dir(d, 4);
  const std::string full = read_bytes(d.journal());
  const JournalScan s = scan_journal(d.journal());
  for (size_t len = jf::kHeaderSize; len <= full.size(); ++len) {
    size_t complete = 0;
    for (size_t i = 0; i < s.offsets.size(); ++i) {
      const size_t end = i + 1 < s.offsets.size() ? s.offsets[i + 1] : full.size();
      if (end <= len) complete = i + 1;
    }
    for (bool zeros : {false, true}) {
      if (zeros && complete == s.offsets.size()) continue;
      std::string bytes = full.substr(0, len);
      if (zeros) std::fill(bytes.begin() + static_cast<long>(s.offsets[complete]), bytes.end(), '\0');
      write_bytes(d.journal(), bytes);
      SCOPED_TRACE("length " + std::to_string(len) + (zeros ? " (zeros)" : ""));
      Journal j(d.path.string());
      Journal::Recovered rec;
      ASSERT_NO_THROW(rec = j.recover());
      EXPECT_EQ(rec.txns.size(), complete);
      EXPECT_EQ(fs::file_size(d.journal()), complete == s.offsets.size() ? full.size() : s.offsets[complete]);
    }
  }
}

TEST(Journal, ABitFlipInTheMiddleRefusesToStartNamingTheOffsetAndChangesNothing) {
  TempDir d;
  make_dir(d, 300, 1);
  JournalScan s = scan_journal(d.journal());
  std::string bytes = read_bytes(d.journal());
  bytes[s.offsets[150] + jf::kFrameSize + 20] ^= 0x04;  // inside record 150's body
  write_bytes(d.journal(), bytes);
  const std::string why = refusal(d);
  EXPECT_TRUE(contains(why, d.journal() + " is corrupt at byte " + std::to_string(s.offsets[150]) + ": record 150 "))
      << why;
  EXPECT_TRUE(contains(why, "the 150 records before it (versions 2-151) are intact")) << why;
  EXPECT_TRUE(contains(why, "149 intact records after the damage (versions 153-301)")) << why;
  EXPECT_TRUE(contains(why, "skillbus wm repair --data " + d.path.string())) << why;
  EXPECT_EQ(why.find('\n'), std::string::npos);
  EXPECT_EQ(read_bytes(d.journal()), bytes);  // the evidence is kept
}

TEST(Journal, ABitFlipInRecord0RefusesToStart) {
  TempDir d;
  make_dir(d, 300, 1);
  std::string bytes = read_bytes(d.journal());
  bytes[jf::kHeaderSize + jf::kFrameSize + 3] ^= 0x80;
  write_bytes(d.journal(), bytes);
  const std::string why = refusal(d);
  EXPECT_TRUE(contains(why, "at byte " + std::to_string(jf::kHeaderSize) + ": record 0 ")) << why;
  EXPECT_TRUE(contains(why, "no record before it is intact (the world stays at version 1)")) << why;
  EXPECT_TRUE(contains(why, "299 intact records after the damage")) << why;
  EXPECT_EQ(read_bytes(d.journal()), bytes);
}

TEST(Journal, ABitFlipInTheLastRecordIsCorruptionNotATornWrite) {
  TempDir d;
  make_dir(d, 300, 1);
  const JournalScan s = scan_journal(d.journal());
  std::string bytes = read_bytes(d.journal());
  bytes[bytes.size() - jf::kFrameSize - 3] ^= 0x01;  // the last record's body, by its end
  write_bytes(d.journal(), bytes);
  const std::string why = refusal(d);
  EXPECT_TRUE(contains(why, "at byte " + std::to_string(s.offsets[299]) + ": record 299 ")) << why;
  EXPECT_TRUE(contains(why, "written completely")) << why;
  EXPECT_EQ(read_bytes(d.journal()), bytes);
}

// One bit flipped anywhere in record 0, a middle record or the last record (or the
// header): the start is refused, or (a flip in a closing frame, which only locates a
// record whose opening frame is damaged) every record comes back intact. Never fewer.
TEST(Journal, NoSingleBitFlipLosesARecordSilently) {
  TempDir d;
  make_dir(d, 5, 3);
  const std::string good = read_bytes(d.journal());
  const JournalScan s = scan_journal(d.journal());
  std::vector<size_t> positions;
  for (size_t i = 0; i < jf::kHeaderSize; ++i) positions.push_back(i);
  for (size_t r : {size_t(0), size_t(2), size_t(4)}) {
    const size_t end = r + 1 < s.offsets.size() ? s.offsets[r + 1] : good.size();
    for (size_t i = s.offsets[r]; i < end; ++i) positions.push_back(i);
  }
  int refused = 0, intact = 0;
  for (size_t pos : positions)
    for (int bit : {0, 3, 7}) {
      std::string bytes = good;
      bytes[pos] ^= static_cast<char>(1 << bit);
      write_bytes(d.journal(), bytes);
      SCOPED_TRACE("byte " + std::to_string(pos) + " bit " + std::to_string(bit));
      Journal j(d.path.string());
      try {
        EXPECT_EQ(j.recover().txns.size(), 5u);
        ++intact;
      } catch (const DataError& e) {
        ++refused;
        EXPECT_EQ(read_bytes(d.journal()), bytes);
      }
    }
  EXPECT_GT(refused, 0);
  EXPECT_EQ(intact, 3 * 3 * static_cast<int>(jf::kFrameSize));  // the closing frames of the three records
}

TEST(Journal, AHugeLengthFieldIsCorruptionInTheMiddleAndAtTheEnd) {
  for (bool last : {false, true}) {
    TempDir d;
    make_dir(d, 300, 1);
    const JournalScan s = scan_journal(d.journal());
    const size_t at = s.offsets[last ? 299 : 150];
    std::string bytes = read_bytes(d.journal());
    bytes[at + 3] = '\x7f';  // length 0x7f......: past the end of the file, and its frame's CRC fails
    write_bytes(d.journal(), bytes);
    const std::string why = refusal(d);
    SCOPED_TRACE(why);
    EXPECT_TRUE(contains(why, "at byte " + std::to_string(at) + ": record " + (last ? "299" : "150"))) << why;
    EXPECT_TRUE(contains(why, "damaged frame")) << why;
    EXPECT_EQ(read_bytes(d.journal()), bytes);
  }
}

TEST(Journal, ADamagedHeaderIsCorruptionAtByte0) {
  TempDir d;
  make_dir(d, 10, 1);
  std::string bytes = read_bytes(d.journal());
  bytes[9] ^= 0x01;  // the base version
  write_bytes(d.journal(), bytes);
  const std::string why = refusal(d);
  EXPECT_TRUE(contains(why, "is corrupt at byte 0: its header")) << why;
  EXPECT_TRUE(contains(why, "10 intact records after the damage")) << why;
}

TEST(Journal, ARecordOutOfVersionOrderIsCorruption) {
  TempDir d;
  {
    Journal j(d.path.string());
    j.recover();
    j.append(txn(0, "a"));
    j.append(txn(5, "b"));  // not the version after the first
  }
  const std::string why = refusal(d);
  EXPECT_TRUE(contains(why, "record 1 applies to version 5 where version 1 was expected")) << why;
}

TEST(Journal, AMissingJournalNextToASnapshotIsAnError) {
  TempDir d;
  make_dir(d, 300, 1);
  fs::remove(d.journal());
  const std::string why = refusal(d);
  EXPECT_TRUE(contains(why, d.journal() + " is missing, but " + d.snapshot() + " (version 1) is there")) << why;
  EXPECT_FALSE(fs::exists(d.journal()));
}

TEST(Journal, AMissingSnapshotThatTheJournalGoesOnFromIsAnError) {
  TempDir d;
  make_dir(d, 300, 1);
  fs::remove(d.snapshot());
  const std::string why = refusal(d);
  EXPECT_TRUE(contains(why, d.snapshot() + " is missing, but " + d.journal() +
                                " goes on from the snapshot at version 1")) << why;
}

TEST(Journal, ACorruptSnapshotIsAnError) {
  TempDir d;
  make_dir(d, 3, 1);
  std::string bytes = read_bytes(d.snapshot());
  bytes[bytes.size() - 2] ^= 0x20;
  write_bytes(d.snapshot(), bytes);
  const std::string why = refusal(d);
  EXPECT_TRUE(contains(why, d.snapshot() + " is corrupt: its checksum does not match")) << why;
  EXPECT_EQ(read_bytes(d.snapshot()), bytes);
}

TEST(Journal, ASnapshotOlderThanTheJournalIsAnError) {
  TempDir d;
  make_dir(d, 3, 1);
  const std::string old_snapshot = read_bytes(d.snapshot());
  {
    Journal j(d.path.string());
    j.recover();
    skillbus_msgs::wm_snapshot_t s{};
    s.world.version = 4;
    j.write_snapshot(s);
  }
  write_bytes(d.snapshot(), old_snapshot);  // version 1, the journal goes on from 4
  const std::string why = refusal(d);
  EXPECT_TRUE(contains(why, "goes on from version 4, but " + d.snapshot() + " is at version 1")) << why;
}

TEST(Journal, ASnapshotStartsAFreshJournal) {
  TempDir d;
  {
    Journal j(d.path.string());
    j.recover();
    j.append(txn(0, "a"));
    skillbus_msgs::wm_snapshot_t s{};
    s.world.version = 1;
    j.write_snapshot(s);
    EXPECT_EQ(j.records_since_snapshot(), 0);
    j.append(txn(1, "b"));
  }
  Journal k(d.path.string());
  auto rec = k.recover();
  ASSERT_TRUE(rec.snapshot);
  EXPECT_EQ(rec.snapshot->version(), 1);
  ASSERT_EQ(rec.txns.size(), 1u);
  EXPECT_EQ(rec.txns[0].ops[0].element.label, "b");
  EXPECT_EQ(scan_journal(d.journal()).base_version, 1);
}

// A crash after the new snapshot is in place and before the new journal replaced the old
// one: the old journal's records are in the snapshot, and are skipped.
TEST(Journal, ACrashBetweenTheSnapshotAndTheNewJournalLosesNothing) {
  TempDir d;
  make_dir(d, 10);
  const std::string old_journal = read_bytes(d.journal());
  {
    Journal j(d.path.string());
    j.recover();
    skillbus_msgs::wm_snapshot_t s{};
    s.world.version = 10;
    j.write_snapshot(s);
  }
  write_bytes(d.journal(), old_journal);
  {
    Journal j(d.path.string());
    auto rec = j.recover();
    EXPECT_EQ(rec.snapshot->version(), 10);
    EXPECT_TRUE(rec.txns.empty());
    j.append(txn(10, "after"));  // goes on in the old journal: still in order
  }
  Journal j(d.path.string());
  auto rec = j.recover();
  ASSERT_EQ(rec.txns.size(), 1u);
  EXPECT_EQ(rec.txns[0].ops[0].element.label, "after");
}

// A write that fails half-way (the file size limit: the first bytes go in, then EFBIG)
// is cut off again: the next record follows the last good one, not the fragment.
TEST(Journal, AFailedWriteIsCutOffBeforeTheNextRecord) {
  TempDir d;
  make_dir(d, 3);
  {
    Journal j(d.path.string());
    j.recover();
    const auto size = fs::file_size(d.journal());
    rlimit old{};
    ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
    auto* previous = std::signal(SIGXFSZ, SIG_IGN);
    rlimit small = old;
    small.rlim_cur = size + 30;
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
    EXPECT_THROW(j.append(txn(3, "does not fit")), WmError);
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &old), 0);
    std::signal(SIGXFSZ, previous);
    EXPECT_EQ(fs::file_size(d.journal()), size);
    j.append(txn(3, "fits"));
  }
  Journal j(d.path.string());
  auto rec = j.recover();
  ASSERT_EQ(rec.txns.size(), 4u);
  EXPECT_EQ(rec.txns[3].ops[0].element.label, "fits");
  EXPECT_TRUE(rec.note.empty()) << rec.note;
}

TEST(Journal, OneProcessAtATimeUsesADataDirectory) {
  TempDir d;
  Journal j(d.path.string());
  try {
    Journal k(d.path.string());
    FAIL() << "a second journal opened a locked directory";
  } catch (const WmError& e) {
    EXPECT_TRUE(contains(e.what(), d.path.string() + " is in use by another process (pid " +
                                       std::to_string(::getpid()))) << e.what();
  }
  EXPECT_EQ(repair_data_dir(d.path.string()).exit_code, 1);
}

TEST(JournalRepair, KeepsTheIntactPrefixAndTheOriginalAside) {
  TempDir d;
  make_dir(d, 300, 1);
  const JournalScan s = scan_journal(d.journal());
  std::string bytes = read_bytes(d.journal());
  bytes[s.offsets[150] + 5] ^= 0x40;  // record 150's frame
  write_bytes(d.journal(), bytes);
  const RepairResult r = repair_data_dir(d.path.string());
  EXPECT_EQ(r.exit_code, 0) << r.message;
  EXPECT_TRUE(contains(r.message, "was corrupt at byte " + std::to_string(s.offsets[150]))) << r.message;
  EXPECT_TRUE(contains(r.message, "kept the 150 intact records before it (versions 2-151)")) << r.message;
  EXPECT_TRUE(contains(r.message, "kept unchanged as " + d.journal() + ".corrupt")) << r.message;
  EXPECT_EQ(read_bytes(d.journal() + ".corrupt"), bytes);
  EXPECT_EQ(read_bytes(d.journal()), bytes.substr(0, s.offsets[150]));
  Journal j(d.path.string());
  auto rec = j.recover();
  ASSERT_EQ(rec.txns.size(), 150u);
  EXPECT_EQ(rec.txns[149].ops[0].element.label, "r150");
}

TEST(JournalRepair, ASecondRepairKeepsTheFirstOriginal) {
  TempDir d;
  for (int round = 0; round < 2; ++round) {
    make_dir(d, 5);  // (round 2: the repaired journal, records 0-4 again)
    std::string bytes = read_bytes(d.journal());
    bytes[jf::kHeaderSize + 1] ^= 0x01;  // record 0's frame
    write_bytes(d.journal(), bytes);
    EXPECT_EQ(repair_data_dir(d.path.string()).exit_code, 0);
  }
  EXPECT_TRUE(fs::exists(d.journal() + ".corrupt"));
  EXPECT_TRUE(fs::exists(d.journal() + ".corrupt.2"));
  EXPECT_EQ(recovered_count(d), 0u);
}

TEST(JournalRepair, NothingToRepairInAnIntactOrTornJournal) {
  TempDir d;
  make_dir(d, 3);
  RepairResult r = repair_data_dir(d.path.string());
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(contains(r.message, "nothing to repair")) << r.message;
  fs::resize_file(d.journal(), fs::file_size(d.journal()) - 2);
  const std::string torn = read_bytes(d.journal());
  r = repair_data_dir(d.path.string());
  EXPECT_TRUE(contains(r.message, "torn last record")) << r.message;
  EXPECT_EQ(read_bytes(d.journal()), torn);
  EXPECT_FALSE(fs::exists(d.journal() + ".corrupt"));
}

TEST(JournalRepair, AMissingJournalGoesOnFromTheSnapshotAMissingSnapshotCannotBeRepaired) {
  {
    TempDir d;
    make_dir(d, 3, 7);
    fs::remove(d.journal());
    const RepairResult r = repair_data_dir(d.path.string());
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_TRUE(contains(r.message, "wrote an empty journal going on from version 7")) << r.message;
    Journal j(d.path.string());
    auto rec = j.recover();
    EXPECT_EQ(rec.snapshot->version(), 7);
    EXPECT_TRUE(rec.txns.empty());
  }
  {
    TempDir d;
    make_dir(d, 3, 7);
    fs::remove(d.snapshot());
    const std::string journal = read_bytes(d.journal());
    const RepairResult r = repair_data_dir(d.path.string());
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_TRUE(contains(r.message, "cannot repair: " + d.snapshot() + " is missing")) << r.message;
    EXPECT_EQ(read_bytes(d.journal()), journal);
  }
}

// ---------------------------------------------------------------- background snapshots

namespace {

// A world of n cubes, each on the table (the relations make the snapshot's second part).
WorldImage world_of(int n, int64_t version) {
  Ontology& onto = skillbus::wm::test::ontology();
  WorldStore store(onto);
  std::vector<Element> elements{Element{"skiros:Table-1", "skiros:Table", "table", {}}};
  std::vector<Relation> relations;
  for (int i = 0; i < n; ++i) {
    const std::string id = "skiros:Cube-" + std::to_string(i + 2);
    elements.push_back(Element{id, "skiros:Cube", "c" + std::to_string(i),
                               {{"skiros:PositionX", {0.01 * i}}, {"skiros:Size", {0.05}}}});
    relations.push_back(Relation{"skiros:Table-1", "skiros:contain", id});
  }
  store.reset(elements, relations, version, 1);
  return store.image();
}

// Holds the snapshot thread at one step until released.
struct Gate {
  std::mutex mu;
  std::condition_variable cv;
  std::string at;       // the step it waits at
  bool reached = false, open = false;
  std::function<void(const char*)> hook() {
    return [this](const char* step) {
      if (at != step) return;
      std::unique_lock<std::mutex> lock(mu);
      reached = true;
      cv.notify_all();
      cv.wait(lock, [this] { return open; });
    };
  }
  void wait_reached() {
    std::unique_lock<std::mutex> lock(mu);
    ASSERT_TRUE(cv.wait_for(lock, std::chrono::seconds(20), [this] { return reached; })) << "never reached " << at;
  }
  void release() {
    std::lock_guard<std::mutex> lock(mu);
    open = true;
    cv.notify_all();
  }
};

}  // namespace

// The file a background snapshot writes piece by piece is byte for byte the encoding of
// the whole message (the format the server always wrote), and reads back the same.
TEST(Snapshot, WrittenInPiecesItIsTheEncodingOfTheWholeMessage) {
  TempDir d;
  fs::create_directories(d.path);
  const std::string a = (d.path / "pieces").string(), b = (d.path / "whole").string();
  SnapshotData data;
  data.world = world_of(300, 7);
  skillbus_msgs::wm_commit_t c{};
  c.client_id = "c";
  c.request_id = 3;
  c.version = 7;
  data.recent.push_back(c);
  skillbus_msgs::wm_snapshot_t whole{};
  whole.world.version = 7;
  whole.world.next_id = data.world.next_id;
  whole.world.total = 301;
  for (const auto& e : data.world.elements) whole.world.elements.push_back(to_msg(*e));
  whole.world.num_elements = 301;
  for (const auto& r : data.world.relations) whole.world.relations.push_back(to_msg(*r));
  whole.world.num_relations = 300;
  whole.recent = data.recent;
  whole.num_recent = 1;
  {
    Journal j(a);
    j.recover();
    j.write_snapshot(data);
    Journal k(b);
    k.recover();
    k.write_snapshot(whole);
  }
  EXPECT_EQ(read_bytes(a + "/snapshot.bin"), read_bytes(b + "/snapshot.bin"));
  SnapshotFile f(a + "/snapshot.bin");
  EXPECT_EQ(f.version(), 7);
  std::vector<std::string> ids;
  f.for_each_element([&](skillbus_msgs::wm_element_t& m) { ids.push_back(m.id); });
  long relations = 0;
  f.for_each_relation([&](skillbus_msgs::wm_relation_t&) { ++relations; });
  ASSERT_EQ(ids.size(), 301u);
  EXPECT_EQ(ids.front(), "skiros:Cube-10");  // id order
  EXPECT_EQ(relations, 300);
  ASSERT_EQ(f.recent().size(), 1u);
  EXPECT_EQ(f.recent()[0].request_id, 3);
}

// While the snapshot is being written (held at each of its steps), appends go on and
// return at once; the records appended meanwhile, also those appended after the new
// journal was written and before it replaced the old one, are all in the new journal.
TEST(Snapshot, InTheBackgroundItDoesNotHoldCommitsBackAndLosesNone) {
  for (const char* step : {"written", "renamed", "journal"}) {
    SCOPED_TRACE(step);
    TempDir d;
    int64_t v = 0;
    {
      Journal j(d.path.string());
      j.recover();
      for (; v < 50; ++v) j.append(txn(v, "r" + std::to_string(v)));
      Gate gate;
      gate.at = step;
      j.test_hook = gate.hook();
      ASSERT_TRUE(j.start_snapshot(SnapshotData{world_of(2000, v), {}}));
      gate.wait_reached();
      EXPECT_TRUE(j.snapshot_running());
      EXPECT_FALSE(j.start_snapshot(SnapshotData{world_of(1, v), {}}));  // one at a time
      const auto t0 = std::chrono::steady_clock::now();
      for (int i = 0; i < 30; ++i, ++v) j.append(txn(v, "r" + std::to_string(v)));
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      EXPECT_TRUE(j.snapshot_running());  // all 30 went in while the snapshot was held
      EXPECT_LT(ms / 30, 50.0);
      gate.release();
      j.wait_for_snapshot();
      EXPECT_FALSE(j.snapshot_running());
      EXPECT_EQ(j.snapshots_written(), 1);
      EXPECT_EQ(j.records_since_snapshot(), 30);
      for (int i = 0; i < 5; ++i, ++v) j.append(txn(v, "r" + std::to_string(v)));  // into the new journal
    }
    const JournalScan s = scan_journal(d.journal());
    EXPECT_EQ(s.base_version, 50);
    EXPECT_EQ(s.txns.size(), 35u);
    Journal k(d.path.string());
    auto rec = k.recover();
    ASSERT_TRUE(rec.snapshot);
    EXPECT_EQ(rec.snapshot->version(), 50);
    EXPECT_EQ(rec.snapshot->total(), 2001);
    ASSERT_EQ(rec.txns.size(), 35u);
    EXPECT_EQ(rec.txns.front().ops[0].element.label, "r50");
    EXPECT_EQ(rec.txns.back().ops[0].element.label, "r84");
  }
}

// A process killed (SIGKILL) while its snapshot is written in the background, at each of
// the snapshot's steps and at random moments, with appends going on: every append that
// returned is recovered, in order, and the data directory always starts.
TEST(Snapshot, AKillDuringABackgroundSnapshotLosesNoAcknowledgedRecord) {
  std::vector<std::string> steps{"written", "renamed", "journal"};
  for (int i = 0; i < 6; ++i) steps.push_back("random");
  unsigned seed = static_cast<unsigned>(::getpid());
  for (const auto& step : steps) {
    SCOPED_TRACE(step);
    TempDir d;
    int acks[2], at[2];
    ASSERT_EQ(::pipe(acks), 0);
    ASSERT_EQ(::pipe(at), 0);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {  // appends until killed; a snapshot every 40 records, in the background
      ::close(acks[0]);
      ::close(at[0]);
      Journal j(d.path.string());
      j.recover();
      if (step != "random")
        j.test_hook = [&](const char* s) {
          if (step != s) return;
          const char c = 'x';
          [[maybe_unused]] ssize_t n = ::write(at[1], &c, 1);
          for (;;) ::pause();  // held here: the kill comes while appends go on
        };
      for (int64_t v = 0;; ++v) {
        j.append(txn(v, "r" + std::to_string(v)));
        const int64_t done = v + 1;
        if (::write(acks[1], &done, sizeof done) != sizeof done) std::_Exit(3);
        if (done % 40 == 0 && j.snapshot_due(40)) j.start_snapshot(SnapshotData{world_of(3000, done), {}});
      }
    }
    ::close(acks[1]);
    ::close(at[1]);
    int64_t acked = 0;
    auto read_ack = [&] {
      int64_t x;
      ASSERT_EQ(::read(acks[0], &x, sizeof x), static_cast<ssize_t>(sizeof x));
      acked = x;
    };
    if (step == "random") {
      const int64_t until = 45 + static_cast<int64_t>(rand_r(&seed) % 200);
      while (acked < until) read_ack();
      ::usleep(rand_r(&seed) % 3000);
    } else {
      char c;
      ASSERT_EQ(::read(at[0], &c, 1), 1);  // the snapshot thread is at the step
      // Acks come in order: read until appends past the snapshot's start (record 40) are
      // acknowledged, so the kill comes while appends go on, however the threads ran.
      while (acked < 45) read_ack();
    }
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
    for (;;) {  // acknowledgements still in the pipe count too
      int64_t x;
      if (::read(acks[0], &x, sizeof x) != static_cast<ssize_t>(sizeof x)) break;
      acked = x;
    }
    ::close(acks[0]);
    ::close(at[0]);
    Journal j(d.path.string());
    Journal::Recovered rec;
    ASSERT_NO_THROW(rec = j.recover());
    const int64_t base = rec.snapshot ? rec.snapshot->version() : 0;
    const int64_t last = base + static_cast<int64_t>(rec.txns.size());
    EXPECT_GE(last, acked);       // nothing acknowledged is lost
    EXPECT_LE(last, acked + 1);   // (the append in flight may have been durable)
    for (size_t i = 0; i < rec.txns.size(); ++i)
      ASSERT_EQ(rec.txns[i].ops[0].element.label, "r" + std::to_string(base + static_cast<int64_t>(i)));
    if (step != "random") {
      EXPECT_GT(acked, 40);
    }
  }
}

// The scene's side files come in generations by world version: the one in force is the
// newest not newer than the snapshot, so files written for a scene change whose snapshot
// a crash prevented never meet the old snapshot's world.
TEST(JournalSceneFiles, TheGenerationInForceIsTheNewestNotNewerThanTheSnapshot) {
  TempDir d;
  Journal j(d.path.string());
  j.recover();
  j.write_scene_files(3, "imports 3", "extra 3");
  j.write_scene_files(7, "imports 7", "extra 7");
  j.write_scene_files(9, "imports 9", "extra 9");  // its snapshot (9) never came
  const Journal::SceneFiles f = j.settle_scene_files(8);
  EXPECT_EQ(f.version, 7);
  EXPECT_EQ(f.imports, "imports 7");
  EXPECT_EQ(f.extra, "extra 7");
  EXPECT_TRUE(contains(f.extra_path, "scene_extra.7.ttl")) << f.extra_path;
  // The replaced generation (3) and the one that never got its snapshot (9) are gone.
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(d.path)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"journal.bin", "lock", "scene_extra.7.ttl", "scene_imports.7.ttl"}));
}

TEST(JournalSceneFiles, FilesWithoutAVersionAreTheGenerationOfVersion0AndANewerOneReplacesThem) {
  TempDir d;
  Journal j(d.path.string());
  j.recover();
  write_bytes((d.path / "scene_extra.ttl").string(), "old extra");  // a data directory of an earlier skillbus
  Journal::SceneFiles f = j.settle_scene_files(5);
  EXPECT_EQ(f.version, 0);
  EXPECT_EQ(f.extra, "old extra");
  EXPECT_EQ(f.imports, "");
  j.write_scene_files(6, "", "new extra");
  f = j.settle_scene_files(6);
  EXPECT_EQ(f.extra, "new extra");
  EXPECT_FALSE(fs::exists(d.path / "scene_extra.ttl"));
  // An empty generation replaces a full one, and once in force needs no files.
  j.write_scene_files(8, "", "");
  f = j.settle_scene_files(8);
  EXPECT_EQ(f.extra, "");
  EXPECT_FALSE(fs::exists(d.path / "scene_extra.6.ttl"));
  EXPECT_FALSE(fs::exists(d.path / "scene_extra.8.ttl"));
  // With no generation on disk, an empty one is not written at all.
  j.write_scene_files(9, "", "");
  EXPECT_FALSE(fs::exists(d.path / "scene_extra.9.ttl"));
}

TEST(JournalSceneFiles, NoGenerationNotNewerThanTheSnapshotMeansNoSceneFilesAndLeftoversAreRemoved) {
  TempDir d;
  Journal j(d.path.string());
  j.recover();
  j.write_scene_files(2, "i", "e");
  write_bytes((d.path / "scene_extra.4.ttl.tmp").string(), "cut short");
  write_bytes((d.path / "scene_extra.notaversion.ttl").string(), "not ours");  // left alone
  const Journal::SceneFiles f = j.settle_scene_files(1);
  EXPECT_EQ(f.version, 0);
  EXPECT_EQ(f.imports + f.extra, "");
  EXPECT_FALSE(fs::exists(d.path / "scene_extra.2.ttl"));
  EXPECT_FALSE(fs::exists(d.path / "scene_extra.4.ttl.tmp"));
  EXPECT_TRUE(fs::exists(d.path / "scene_extra.notaversion.ttl"));
  j.write_scene_files(2, "i", "e");
  j.remove_scene_files(2);
  EXPECT_FALSE(fs::exists(d.path / "scene_imports.2.ttl"));
}

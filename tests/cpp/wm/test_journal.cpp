#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "skillbus/wm/journal.hpp"
#include "skillbus/wm/model.hpp"

using namespace skillbus::wm;
namespace fs = std::filesystem;

namespace {

struct TempDir {
  fs::path path = fs::temp_directory_path() / ("wm-journal-" + std::to_string(::getpid()) + "-" +
                                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
  TempDir() { fs::remove_all(path); }
  ~TempDir() { fs::remove_all(path); }
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

}  // namespace

TEST(Journal, RecoversEveryAppendedRecordInOrder) {
  TempDir d;
  {
    Journal j(d.path);
    j.recover();
    for (int i = 0; i < 50; ++i) j.append(txn(i, "c" + std::to_string(i)));
  }
  Journal j(d.path);
  auto rec = j.recover();
  ASSERT_EQ(rec.txns.size(), 50u);
  EXPECT_EQ(rec.txns[49].ops[0].element.label, "c49");
  EXPECT_TRUE(rec.note.empty());
}

TEST(Journal, ATornLastRecordIsCutOffAndTheRestKept) {
  TempDir d;
  {
    Journal j(d.path);
    j.recover();
    for (int i = 0; i < 3; ++i) j.append(txn(i, "x"));
  }
  const auto size = fs::file_size(d.path / "journal.bin");
  fs::resize_file(d.path / "journal.bin", size - 5);  // a crash in the middle of the last write
  {
    Journal j(d.path);
    auto rec = j.recover();
    EXPECT_EQ(rec.txns.size(), 2u);
    EXPECT_NE(rec.note.find("torn"), std::string::npos);
    j.append(txn(2, "again"));  // appends after the cut, not after the garbage
  }
  Journal j(d.path);
  auto rec = j.recover();
  ASSERT_EQ(rec.txns.size(), 3u);
  EXPECT_EQ(rec.txns[2].ops[0].element.label, "again");
}

TEST(Journal, ACorruptedRecordEndsTheJournal) {
  TempDir d;
  {
    Journal j(d.path);
    j.recover();
    for (int i = 0; i < 3; ++i) j.append(txn(i, "x"));
  }
  std::fstream f(d.path / "journal.bin", std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(-3, std::ios::end);
  f.put('\x7f');  // a flipped byte in the last record: its CRC fails
  f.close();
  Journal j(d.path);
  EXPECT_EQ(j.recover().txns.size(), 2u);
}

TEST(Journal, ASnapshotStartsAFreshJournal) {
  TempDir d;
  Journal j(d.path);
  j.recover();
  j.append(txn(0, "a"));
  skillbus_msgs::wm_snapshot_t s{};
  s.world.version = 1;
  j.write_snapshot(s);
  j.append(txn(1, "b"));
  Journal k(d.path);
  auto rec = k.recover();
  ASSERT_TRUE(rec.snapshot.has_value());
  EXPECT_EQ(rec.snapshot->world.version, 1);
  ASSERT_EQ(rec.txns.size(), 1u);
  EXPECT_EQ(rec.txns[0].ops[0].element.label, "b");
}

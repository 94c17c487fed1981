#include "skillbus/wm/journal.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "skillbus/bus.hpp"
#include "skillbus/log.hpp"
#include "skillbus/wm/convert.hpp"

namespace skillbus::wm {

namespace fmt = journal_format;

namespace {

const char* kLog = "wm_journal";
const char kJournalMagic[] = "SBWMJNL1";   // 8 bytes, no terminator written
const char kSnapshotMagic[] = "SBWMSNP1";

std::string sys_error(const std::string& what) { return what + ": " + std::strerror(errno); }

void write_all(int fd, const void* data, size_t n, const std::string& path) {
  const auto* p = static_cast<const uint8_t*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w < 0) throw WmError(sys_error("cannot write " + path));
    p += w;
    n -= static_cast<size_t>(w);
  }
}

void put_u32(uint8_t* b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[i] = uint8_t(v >> (8 * i));
}
void put_i64(uint8_t* b, int64_t v) {
  for (int i = 0; i < 8; ++i) b[i] = uint8_t(uint64_t(v) >> (8 * i));
}
uint32_t get_u32(const uint8_t* b) { return b[0] | (b[1] << 8) | (b[2] << 16) | (uint32_t(b[3]) << 24); }
int64_t get_i64(const uint8_t* b) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | b[i];
  return static_cast<int64_t>(v);
}

uint32_t crc(const uint8_t* d, size_t n) { return static_cast<uint32_t>(crc32(0L, d, static_cast<uInt>(n))); }

bool exists(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) == 0) return true;
  if (errno == ENOENT) return false;
  throw WmError(sys_error("cannot look at " + path));
}

std::string read_all(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw WmError(sys_error("cannot read " + path));
  std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw WmError("cannot read " + path);
  return bytes;
}

void sync_dir(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw WmError(sys_error("cannot open directory " + dir + " to sync it"));
  const int r = ::fsync(fd);
  const int e = errno;
  ::close(fd);
  errno = e;
  if (r != 0) throw WmError(sys_error("cannot sync directory " + dir));
}

void sync_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw WmError(sys_error("cannot open " + path + " to sync it"));
  const int r = ::fsync(fd);
  const int e = errno;
  ::close(fd);
  errno = e;
  if (r != 0) throw WmError(sys_error("cannot sync " + path));
}

// Writes `name` in `dir` so that it is either the old file or the whole new one, on disk
// on return: beside, synced, renamed, the directory synced.
// Writes `bytes` as a new file at `path`, on disk on return; on failure no file is left.
void write_file_synced(const std::string& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) throw WmError(sys_error("cannot create " + path));
  try {
    write_all(fd, bytes.data(), bytes.size(), path);
    if (::fsync(fd) != 0) throw WmError(sys_error("cannot sync " + path));
  } catch (...) {
    ::close(fd);
    ::unlink(path.c_str());
    throw;
  }
  ::close(fd);
}

void replace_file_durably(const std::string& dir, const std::string& name, const std::string& bytes) {
  const std::string tmp = dir + "/" + name + ".tmp", path = dir + "/" + name;
  write_file_synced(tmp, bytes);
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string e = sys_error("cannot rename " + tmp + " to " + path);
    ::unlink(tmp.c_str());
    throw WmError(e);
  }
  sync_dir(dir);
}

// Renames DIR/name.tmp (written and synced) to DIR/name and syncs the directory.
void rename_into_place(const std::string& dir, const std::string& name) {
  const std::string tmp = dir + "/" + name + ".tmp", path = dir + "/" + name;
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string e = sys_error("cannot rename " + tmp + " to " + path);
    ::unlink(tmp.c_str());
    throw WmError(e);
  }
  sync_dir(dir);
}

std::string journal_header(int64_t base_version) {
  uint8_t h[fmt::kHeaderSize];
  std::memcpy(h, kJournalMagic, 8);
  put_i64(h + 8, base_version);
  put_u32(h + 16, crc(h, 16));
  return std::string(reinterpret_cast<const char*>(h), sizeof h);
}

// A record's frame: valid when its own CRC matches and the length is possible.
struct Frame {
  uint32_t len = 0, body_crc = 0;
};
bool frame_at(const uint8_t* b, size_t avail, Frame& f) {
  if (avail < fmt::kFrameSize) return false;
  f.len = get_u32(b);
  f.body_crc = get_u32(b + 4);
  return crc(b, 8) == get_u32(b + 8) && f.len > 0 && f.len <= fmt::kMaxBody;
}

// A whole, intact record at pos: a valid frame, inside the file, its body's CRC right.
bool intact_at(const uint8_t* b, size_t size, size_t pos, Frame& f) {
  if (pos >= size || !frame_at(b + pos, size - pos, f)) return false;
  if (size - pos < fmt::kRecordOverhead + uint64_t(f.len)) return false;
  return crc(b + pos + fmt::kFrameSize, f.len) == f.body_crc;
}

size_t find_intact(const uint8_t* b, size_t size, size_t from, Frame& f) {
  for (size_t p = from; p + fmt::kRecordOverhead < size; ++p)
    if (intact_at(b, size, p, f)) return p;
  return std::string::npos;
}

// The closing frame at the very end of the file belongs to a record starting at pos.
bool closing_frame_at_end(const uint8_t* b, size_t size, size_t pos) {
  if (size - pos < fmt::kRecordOverhead) return false;
  Frame f;
  return frame_at(b + size - fmt::kFrameSize, fmt::kFrameSize, f) &&
         size - pos == fmt::kRecordOverhead + uint64_t(f.len);
}

bool all_zero(const uint8_t* b, size_t n) {
  for (size_t i = 0; i < n; ++i)
    if (b[i] != 0) return false;
  return true;
}

std::string plural(long n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// The intact records somewhere after the damage: counted for the report.
void count_after(JournalScan& s, const uint8_t* b, size_t size, size_t from) {
  Frame f;
  size_t p = from;
  while ((p = find_intact(b, size, p, f)) != std::string::npos) {
    skillbus_msgs::wm_txn_t t;
    if (decode_msg(b + p + fmt::kFrameSize, f.len, t)) {
      if (s.intact_after == 0) s.after_first_version = t.expected_version + 1;
      s.after_last_version = t.expected_version + 1;
    }
    ++s.intact_after;
    p += fmt::kRecordOverhead + f.len;
  }
}

JournalScan scan_bytes(const std::string& bytes) {
  using End = JournalScan::End;
  JournalScan s;
  const auto* b = reinterpret_cast<const uint8_t*>(bytes.data());
  const size_t size = bytes.size();
  s.size = size;
  if (size < fmt::kHeaderSize || std::memcmp(b, kJournalMagic, 8) != 0 || crc(b, 16) != get_u32(b + 16)) {
    s.end = End::Corrupt;
    if (size == 0)
      s.why = "the file is empty: it has no journal header";
    else if (size < 8 || std::memcmp(b, kJournalMagic, 8) != 0)
      s.why = "the file does not start with a journal header (SBWMJNL1): not a journal of this format";
    else if (size < fmt::kHeaderSize)
      s.why = "its header is cut short";
    else
      s.why = "its header (the version it goes on from) fails its checksum";
    count_after(s, b, size, std::min(size, fmt::kHeaderSize));
    return s;
  }
  s.header_ok = true;
  s.base_version = get_i64(b + 8);
  size_t pos = fmt::kHeaderSize;
  auto fail = [&](End end, const std::string& why) {
    s.end = end;
    s.why = "record " + std::to_string(s.txns.size()) + " " + why;
  };
  while (pos < size) {
    const size_t rem = size - pos;
    Frame f, g;
    if (frame_at(b + pos, rem, f)) {
      if (rem < fmt::kRecordOverhead + uint64_t(f.len)) {
        fail(End::Torn, "runs past the end of the file (a " + std::to_string(f.len) + "-byte body, " +
                            std::to_string(rem) + " bytes there)");
        break;
      }
      const uint8_t* body = b + pos + fmt::kFrameSize;
      if (crc(body, f.len) != f.body_crc) {
        const bool closed = std::memcmp(b + pos, body + f.len, fmt::kFrameSize) == 0;
        if (closed)
          fail(End::Corrupt, "fails its checksum although it was written completely (its closing frame is there)");
        else if (find_intact(b, size, pos + 1, g) != std::string::npos)
          fail(End::Corrupt, "fails its checksum, and intact records follow it");
        else
          fail(End::Torn, "was not completely written (its body fails its checksum, its closing frame is missing)");
        break;
      }
      skillbus_msgs::wm_txn_t t;
      if (!decode_msg(body, f.len, t)) {
        fail(End::Corrupt, "passes its checksum but does not decode as a transaction");
        break;
      }
      const int64_t want = s.base_version + static_cast<int64_t>(s.txns.size());
      if (t.expected_version != want) {
        fail(End::Corrupt, "applies to version " + std::to_string(t.expected_version) + " where version " +
                               std::to_string(want) + " was expected");
        break;
      }
      s.offsets.push_back(pos);
      s.txns.push_back(std::move(t));
      pos += fmt::kRecordOverhead + f.len;
      continue;
    }
    if (all_zero(b + pos, rem))
      fail(End::Torn, "is " + plural(static_cast<long>(rem), "zero byte", "zero bytes") +
                          " to the end of the file (space extended but never written)");
    else if (find_intact(b, size, pos + 1, g) != std::string::npos)
      fail(End::Corrupt, "has a damaged frame (length or checksum field), and intact records follow it");
    else if (closing_frame_at_end(b, size, pos))
      fail(End::Corrupt, "has a damaged frame (length or checksum field) although it was written completely "
                         "(its closing frame ends the file)");
    else
      fail(End::Torn, "is " + plural(static_cast<long>(rem), "byte", "bytes") + " that are no complete record");
    break;
  }
  s.good_end = pos;
  if (s.end == End::Corrupt) count_after(s, b, size, pos + 1);
  return s;
}

std::string versions(int64_t first, int64_t last) {
  return first == last ? "version " + std::to_string(first)
                       : "versions " + std::to_string(first) + "-" + std::to_string(last);
}

// One line: the file, the offset, the records before it (intact) and from it on (lost).
std::string describe_corruption(const std::string& path, const std::string& dir, const JournalScan& s) {
  const long k = static_cast<long>(s.txns.size());
  std::string m = path + " is corrupt at byte " + std::to_string(s.good_end) + ": " + s.why + "; ";
  if (!s.header_ok)
    m += "no record can be placed without it";
  else if (k == 0)
    m += "no record before it is intact (the world stays at version " + std::to_string(s.base_version) + ")";
  else
    m += "the " + plural(k, "record", "records") + " before it (" +
         versions(s.base_version + 1, s.base_version + k) + ") are intact";
  m += "; affected: ";
  if (s.header_ok) m += "record " + std::to_string(k) + " (version " + std::to_string(s.base_version + k + 1) + ") and ";
  m += "the " + std::to_string(s.size - s.good_end) + " bytes from byte " + std::to_string(s.good_end) + " on";
  if (s.intact_after > 0)
    m += ", holding " + plural(s.intact_after, "intact record", "intact records") + " after the damage (" +
         versions(s.after_first_version, s.after_last_version) + ") that cannot be applied without it";
  m += "; nothing was changed: to go on with the intact records only, run `skillbus wm repair --data " + dir +
       "` (it keeps the original as journal.bin.corrupt)";
  return m;
}

const char* const kRestore = "; nothing was changed: restore it from a backup (the journal holds only the commits after it)";

void put_be32(uint8_t* b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[i] = uint8_t(v >> (24 - 8 * i));
}
void put_be64(uint8_t* b, uint64_t v) {
  for (int i = 0; i < 8; ++i) b[i] = uint8_t(v >> (56 - 8 * i));
}
uint32_t get_be32(const uint8_t* b) { return uint32_t(b[0]) << 24 | uint32_t(b[1]) << 16 | uint32_t(b[2]) << 8 | b[3]; }
uint64_t get_be64(const uint8_t* b) { return uint64_t(get_be32(b)) << 32 | get_be32(b + 4); }

// Writes a snapshot file's body in pieces through a buffer, with its CRC and length
// kept as it goes: the bytes are exactly those of encode_msg(wm_snapshot_t) (LCM's
// encoding: the fingerprint, then each field in order; a nested message without its
// own fingerprint), so the file format is the same as when the message was encoded
// whole, without holding a second copy of a large world as messages and bytes.
class BodyWriter {
 public:
  BodyWriter(int fd, std::string path) : fd_(fd), path_(std::move(path)) { buf_.reserve(kChunk); }
  void bytes(const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    crc_ = static_cast<uint32_t>(crc32(crc_, b, static_cast<uInt>(n)));
    len_ += n;
    buf_.insert(buf_.end(), b, b + n);
    if (buf_.size() >= kChunk) flush();
  }
  void be32(uint32_t v) {
    uint8_t b[4];
    put_be32(b, v);
    bytes(b, 4);
  }
  void be64(uint64_t v) {
    uint8_t b[8];
    put_be64(b, v);
    bytes(b, 8);
  }
  template <class M>
  void nested(const M& m) {  // a message inside another: no fingerprint of its own
    const int n = m._getEncodedSizeNoHash();
    tmp_.resize(static_cast<size_t>(n));
    if (m._encodeNoHash(tmp_.data(), 0, n) != n) throw WmError("cannot encode a snapshot's " + std::string(M::getTypeName()));
    bytes(tmp_.data(), tmp_.size());
  }
  void flush() {
    write_all(fd_, buf_.data(), buf_.size(), path_);
    // Start the write-back of what is written now, without waiting for it: the sync at
    // the end then has little left to do, and the journal's fdatasyncs meanwhile do not
    // queue behind tens of megabytes flushed at once.
    ::sync_file_range(fd_, static_cast<off_t>(flushed_), static_cast<off_t>(buf_.size()), SYNC_FILE_RANGE_WRITE);
    flushed_ += buf_.size();
    buf_.clear();
  }
  uint64_t length() const { return len_; }
  uint32_t crc() const { return crc_; }

 private:
  static constexpr size_t kChunk = 1 << 20;
  int fd_;
  std::string path_;
  std::vector<uint8_t> buf_, tmp_;
  uint64_t flushed_ = fmt::kSnapshotHeaderSize;  // the file's bytes written so far
  uint32_t crc_ = static_cast<uint32_t>(crc32(0L, Z_NULL, 0));
  uint64_t len_ = 0;
};

// snapshot.bin.tmp with the body `body` writes, synced; renamed to snapshot.bin and the
// directory synced by the caller. On failure no file is left.
void write_snapshot_tmp(const std::string& tmp, const std::function<void(BodyWriter&)>& body) {
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) throw WmError(sys_error("cannot create " + tmp));
  try {
    uint8_t h[fmt::kSnapshotHeaderSize] = {0};
    write_all(fd, h, sizeof h, tmp);  // its length and CRC are known at the end
    BodyWriter w(fd, tmp);
    body(w);
    w.flush();
    if (w.length() > UINT32_MAX) throw WmError("a snapshot of " + std::to_string(w.length()) + " bytes is too big");
    std::memcpy(h, kSnapshotMagic, 8);
    put_u32(h + 8, static_cast<uint32_t>(w.length()));
    put_u32(h + 12, w.crc());
    if (::pwrite(fd, h, sizeof h, 0) != static_cast<ssize_t>(sizeof h)) throw WmError(sys_error("cannot write " + tmp));
    if (::fsync(fd) != 0) throw WmError(sys_error("cannot sync " + tmp));
  } catch (...) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  ::close(fd);
}

void snapshot_body(BodyWriter& w, const SnapshotData& d) {
  w.be64(static_cast<uint64_t>(skillbus_msgs::wm_snapshot_t::getHash()));
  w.be64(static_cast<uint64_t>(d.world.version));  // wm_elements_t world
  w.be64(static_cast<uint64_t>(d.world.next_id));
  w.be64(static_cast<uint64_t>(d.world.elements.size()));  // total
  w.be32(static_cast<uint32_t>(d.world.elements.size()));
  for (const auto& e : d.world.elements) w.nested(to_msg(*e));
  w.be32(static_cast<uint32_t>(d.world.relations.size()));
  for (const auto& r : d.world.relations) w.nested(to_msg(*r));
  w.be32(static_cast<uint32_t>(d.recent.size()));  // num_recent
  for (const auto& c : d.recent) w.nested(c);
}

// The lock of a data directory: one process uses it at a time (a server, or a repair).
int lock_dir(const std::string& dir) {
  const std::string path = dir + "/lock";
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (fd < 0) throw WmError(sys_error("cannot open " + path));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    char pid[32] = {0};
    [[maybe_unused]] const ssize_t n = ::pread(fd, pid, sizeof pid - 1, 0);
    ::close(fd);
    errno = e;
    if (e == EWOULDBLOCK)
      throw WmError(dir + " is in use by another process (pid " + std::string(pid[0] ? pid : "?") + " holds " +
                    path + ")");
    throw WmError(sys_error("cannot lock " + path));
  }
  const std::string pid = std::to_string(::getpid());
  if (::ftruncate(fd, 0) == 0) {
    [[maybe_unused]] const ssize_t n = ::pwrite(fd, pid.data(), pid.size(), 0);
  }
  return fd;
}

void make_dir(const std::string& dir) {
  if (::mkdir(dir.c_str(), 0700) == 0) {
    // Its name in the parent must be durable too, or a power loss takes the whole directory.
    std::filesystem::path path = std::filesystem::path(dir).lexically_normal();
    if (!path.has_filename()) path = path.parent_path();  // "a/b/" names b too
    const std::string parent = path.parent_path().string();
    sync_dir(parent.empty() ? "." : parent);
  } else if (errno != EEXIST) {
    throw WmError(sys_error("cannot create data directory " + dir));
  }
}

}  // namespace

JournalScan scan_journal(const std::string& path) { return scan_bytes(read_all(path)); }

// ---------------------------------------------------------------- snapshot files

SnapshotFile::SnapshotFile(const std::string& path) : path_(path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw WmError(sys_error("cannot read " + path));
  struct stat st;
  if (::fstat(fd, &st) != 0) {
    const std::string e = sys_error("cannot read " + path);
    ::close(fd);
    throw WmError(e);
  }
  map_size_ = static_cast<size_t>(st.st_size);
  if (map_size_ > 0) {
    map_ = ::mmap(nullptr, map_size_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (map_ == MAP_FAILED) {
      map_ = nullptr;
      const std::string e = sys_error("cannot read " + path);
      ::close(fd);
      throw WmError(e);
    }
    ::madvise(map_, map_size_, MADV_SEQUENTIAL);
  }
  ::close(fd);
  const auto* b = static_cast<const uint8_t*>(map_);
  const size_t n = map_size_;
  try {
    if (n < 8 || std::memcmp(b, kSnapshotMagic, 8) != 0)
      throw DataError(path + " is not a snapshot of this format (it does not start with SBWMSNP1)" + kRestore);
    if (n < fmt::kSnapshotHeaderSize) throw DataError(path + " is corrupt: its header is cut short" + kRestore);
    const uint32_t len = get_u32(b + 8);
    if (n - fmt::kSnapshotHeaderSize != len)
      throw DataError(path + " is corrupt: it has " + std::to_string(n) + " bytes where its header says " +
                      std::to_string(fmt::kSnapshotHeaderSize + uint64_t(len)) + kRestore);
    if (crc(b + fmt::kSnapshotHeaderSize, len) != get_u32(b + 12))
      throw DataError(path + " is corrupt: its checksum does not match its " + std::to_string(len) + " bytes" + kRestore);
    body_ = b + fmt::kSnapshotHeaderSize;
    size_ = len;
    // The fingerprint and the world's fixed fields; the elements are decoded on demand.
    if (size_ < 8 + 8 + 8 + 8 + 4 ||
        get_be64(body_) != static_cast<uint64_t>(skillbus_msgs::wm_snapshot_t::getHash()))
      undecodable("its fingerprint");
    version_ = static_cast<int64_t>(get_be64(body_ + 8));
    next_id_ = static_cast<int64_t>(get_be64(body_ + 16));
    num_elements_ = static_cast<int32_t>(get_be32(body_ + 32));
    if (num_elements_ < 0) undecodable("its count of elements");
    elements_at_ = 36;
  } catch (...) {
    if (map_) ::munmap(map_, map_size_);
    throw;
  }
}

SnapshotFile::~SnapshotFile() {
  if (map_) ::munmap(map_, map_size_);
}

void SnapshotFile::undecodable(const std::string& what) const {
  throw DataError(path_ + " is corrupt: it passes its checksum but does not decode as a snapshot (" + what + ")" +
                  kRestore);
}

namespace {

// Decodes `count` messages of type M from body[pos...], calling fn on each; returns the
// offset after them. LCM's decoder may throw on a bad string length: that is undecodable.
template <class M, class F>
size_t decode_run(const uint8_t* body, size_t size, size_t pos, int32_t count, F&& fn, const char* what,
                  const std::function<void(const std::string&)>& fail) {
  M m;
  for (int32_t i = 0; i < count; ++i) {
    int n = -1;
    try {
      n = m._decodeNoHash(body, static_cast<int>(pos), static_cast<int>(size - pos));
    } catch (const std::exception&) {
      n = -1;
    }
    if (n < 0) fail(std::string(what) + " " + std::to_string(i));
    pos += static_cast<size_t>(n);
    fn(m);
  }
  return pos;
}

}  // namespace

void SnapshotFile::for_each_element(const std::function<void(skillbus_msgs::wm_element_t&)>& fn) const {
  auto fail = [this](const std::string& w) { undecodable(w); };
  const size_t end = decode_run<skillbus_msgs::wm_element_t>(body_, size_, elements_at_, num_elements_, fn, "element",
                                                              fail);
  auto* self = const_cast<SnapshotFile*>(this);  // where the relations start: known now
  if (end + 4 > size_) undecodable("its count of relations");
  self->relations_at_ = end + 4;
  self->num_relations_ = static_cast<int32_t>(get_be32(body_ + end));
}

void SnapshotFile::for_each_relation(const std::function<void(skillbus_msgs::wm_relation_t&)>& fn) const {
  if (relations_at_ == 0) for_each_element([](skillbus_msgs::wm_element_t&) {});
  auto fail = [this](const std::string& w) { undecodable(w); };
  const size_t end = decode_run<skillbus_msgs::wm_relation_t>(body_, size_, relations_at_, num_relations_, fn,
                                                               "relation", fail);
  auto* self = const_cast<SnapshotFile*>(this);
  if (end + 4 > size_) undecodable("its count of remembered commits");
  self->recent_at_ = end + 4;
  self->num_recent_ = static_cast<int32_t>(get_be32(body_ + end));
}

std::vector<skillbus_msgs::wm_commit_t> SnapshotFile::recent() const {
  if (recent_at_ == 0) for_each_relation([](skillbus_msgs::wm_relation_t&) {});
  std::vector<skillbus_msgs::wm_commit_t> out;
  auto fail = [this](const std::string& w) { undecodable(w); };
  const size_t end = decode_run<skillbus_msgs::wm_commit_t>(
      body_, size_, recent_at_, num_recent_, [&](skillbus_msgs::wm_commit_t& c) { out.push_back(c); },
      "remembered commit", fail);
  if (end != size_) undecodable("bytes after its end");
  return out;
}

skillbus_msgs::wm_snapshot_t SnapshotFile::decode_all() const {
  skillbus_msgs::wm_snapshot_t snap;
  if (!decode_msg(body_, size_, snap)) undecodable("the whole message");
  return snap;
}

// ---------------------------------------------------------------- the journal

Journal::Journal(std::string dir) : dir_(std::move(dir)) {
  make_dir(dir_);
  lock_fd_ = lock_dir(dir_);
}

Journal::~Journal() {
  wait_for_snapshot();
  if (worker_.joinable()) worker_.join();
  if (fd_ >= 0) ::close(fd_);
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

void Journal::start_journal(int64_t base_version) {
  const std::string tmp = dir_ + "/journal.bin.tmp", path = dir_ + "/journal.bin";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0600);
  if (fd < 0) throw WmError(sys_error("cannot create " + tmp));
  const std::string header = journal_header(base_version);
  try {
    write_all(fd, header.data(), header.size(), tmp);
    if (::fsync(fd) != 0) throw WmError(sys_error("cannot sync " + tmp));
    if (::rename(tmp.c_str(), path.c_str()) != 0) throw WmError(sys_error("cannot rename " + tmp + " to " + path));
  } catch (...) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;  // the old journal goes on
  }
  std::lock_guard<std::mutex> lock(mu_);
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
  size_ = header.size();
  records_ = 0;
  attempt_at_ = 0;
  try {
    sync_dir(dir_);
  } catch (const WmError& e) {
    // The new journal has its name, but perhaps not on disk: records appended to it could
    // vanish with the name. No more commits until a restart settles it.
    broken_ = std::string("the journal cannot be used: ") + e.what() + "; restart the server";
    throw WmError(broken_);
  }
}

Journal::Recovered Journal::recover() {
  Recovered out;
  const std::string jpath = dir_ + "/journal.bin", spath = dir_ + "/snapshot.bin";
  const bool has_snapshot = exists(spath), has_journal = exists(jpath);
  if (!has_snapshot && !has_journal) {
    start_journal(0);  // a new data directory
    records_ = 0;
    return out;
  }
  if (has_snapshot) out.snapshot = std::make_shared<SnapshotFile>(spath);
  const int64_t snap_version = has_snapshot ? out.snapshot->version() : 0;
  const std::string v = std::to_string(snap_version);
  if (!has_journal)
    throw DataError(jpath + " is missing, but " + spath + " (version " + v + ") is there: the commits after version " +
                    v + " would be lost; nothing was changed: restore journal.bin, or run `skillbus wm repair --data " +
                    dir_ + "` to go on from the snapshot without them");
  JournalScan s = scan_journal(jpath);
  if (s.end == JournalScan::End::Corrupt) throw DataError(describe_corruption(jpath, dir_, s));
  const std::string b = std::to_string(s.base_version);
  if (!has_snapshot && s.base_version != 0)
    throw DataError(spath + " is missing, but " + jpath + " goes on from the snapshot at version " + b +
                    ": the world up to version " + b + " is gone; nothing was changed: restore snapshot.bin, "
                    "or move " + dir_ + " aside to start anew");
  if (has_snapshot && s.base_version > snap_version)
    throw DataError(jpath + " goes on from version " + b + ", but " + spath + " is at version " + v +
                    ", older: the commits after version " + v + " up to version " + b +
                    " are in neither file; nothing was changed: restore the snapshot of version " + b);
  // From here on the files are consistent; what the server will rely on is made durable
  // (a process that died before may have left it in the page cache only).
  for (const auto& tmp : {jpath + ".tmp", spath + ".tmp"})
    if (exists(tmp) && ::unlink(tmp.c_str()) != 0) throw WmError(sys_error("cannot remove " + tmp));
  if (s.end == JournalScan::End::Torn) {
    const int fd = ::open(jpath.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0 || ::ftruncate(fd, static_cast<off_t>(s.good_end)) != 0 || ::fsync(fd) != 0) {
      const std::string e = sys_error("cannot cut the torn record off " + jpath);
      if (fd >= 0) ::close(fd);
      throw WmError(e);
    }
    ::close(fd);
    const int64_t last = s.base_version + static_cast<int64_t>(s.txns.size());
    out.note = "cut off a torn record at byte " + std::to_string(s.good_end) + " of " + jpath + " (" +
               plural(static_cast<long>(s.size - s.good_end), "byte", "bytes") + " after the last complete record" +
               (s.txns.empty() ? "" : ", which made version " + std::to_string(last)) + "): " + s.why +
               "; a write that was never acknowledged";
    SB_WARN(kLog, out.note);
  }
  sync_file(jpath);
  if (has_snapshot) sync_file(spath);
  sync_dir(dir_);
  for (auto& t : s.txns)
    if (t.expected_version >= snap_version) out.txns.push_back(std::move(t));
  records_ = static_cast<long>(out.txns.size());
  fd_ = ::open(jpath.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd_ < 0) throw WmError(sys_error("cannot open " + jpath));
  size_ = s.good_end;
  return out;
}

void Journal::append(const skillbus_msgs::wm_txn_t& txn) {
  const std::string path = dir_ + "/journal.bin";
  std::lock_guard<std::mutex> lock(mu_);  // the background snapshot's switch to a new journal
  if (!broken_.empty()) throw WmError(broken_);
  if (fd_ < 0) throw WmError("the journal of " + dir_ + " is not open: recover() first");
  const Bytes body = encode_msg(txn);
  if (body.size() > fmt::kMaxBody) throw WmError("a transaction of " + std::to_string(body.size()) + " bytes is too big");
  Bytes rec(fmt::kRecordOverhead + body.size());
  put_u32(rec.data(), static_cast<uint32_t>(body.size()));
  put_u32(rec.data() + 4, crc(body.data(), body.size()));
  put_u32(rec.data() + 8, crc(rec.data(), 8));
  std::copy(body.begin(), body.end(), rec.begin() + fmt::kFrameSize);
  std::copy(rec.begin(), rec.begin() + fmt::kFrameSize, rec.end() - fmt::kFrameSize);
  try {
    write_all(fd_, rec.data(), rec.size(), path);  // one write: O_APPEND keeps it whole
  } catch (const WmError& e) {
    // Take back what part of the record got written, or the next record would follow garbage.
    if (::ftruncate(fd_, static_cast<off_t>(size_)) != 0)
      broken_ = std::string("the journal cannot be used: ") + e.what() + ", and " +
                sys_error("cannot cut the partial record off") + "; restart the server";
    throw;
  }
  if (::fdatasync(fd_) != 0) {
    // After a failed sync the kernel may have dropped the pages: nothing written since
    // the last good sync can be trusted to be on disk, and a second sync proves nothing.
    broken_ = sys_error("cannot sync " + path) + "; no commit can be made durable until the server restarts";
    throw WmError(broken_);
  }
  size_ += rec.size();
  ++records_;
}

void Journal::write_snapshot(const skillbus_msgs::wm_snapshot_t& snapshot) {
  wait_for_snapshot();
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (!broken_.empty()) throw WmError(broken_);
  }
  const Bytes body = encode_msg(snapshot);
  // The snapshot first: until the new journal replaces the old one, the old journal has
  // every commit (recovery skips those the snapshot has).
  write_snapshot_tmp(dir_ + "/snapshot.bin.tmp", [&](BodyWriter& w) { w.bytes(body.data(), body.size()); });
  rename_into_place(dir_, "snapshot.bin");
  start_journal(snapshot.world.version);
}

void Journal::write_snapshot(const SnapshotData& snapshot) {
  wait_for_snapshot();
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (!broken_.empty()) throw WmError(broken_);
  }
  write_snapshot_file(snapshot);
  start_journal(snapshot.world.version);
  std::lock_guard<std::mutex> lock(mu_);
  ++snapshots_;
}

void Journal::write_snapshot_file(const SnapshotData& snapshot) const {
  write_snapshot_tmp(dir_ + "/snapshot.bin.tmp", [&](BodyWriter& w) {
    snapshot_body(w, snapshot);
    if (test_hook) {
      w.flush();
      test_hook("written");
    }
  });
  rename_into_place(dir_, "snapshot.bin");
  if (test_hook) test_hook("renamed");
}

bool Journal::start_snapshot(SnapshotData snapshot) {
  std::unique_lock<std::mutex> lock(mu_);
  if (running_ || !broken_.empty()) return false;
  if (worker_.joinable()) worker_.join();  // the last one has ended (running_ is false)
  running_ = true;
  // The records up to the snapshot's version end where the journal ends now: the new
  // journal gets a copy of what follows.
  const uint64_t tail_from = size_;
  const long records_before = records_;
  worker_ = std::thread([this, s = std::move(snapshot), tail_from, records_before]() mutable {
    background(std::move(s), tail_from, records_before);
  });
  return true;
}

void Journal::background(SnapshotData snapshot, uint64_t tail_from, long records_before) {
  const int64_t version = snapshot.world.version;
  const auto t0 = std::chrono::steady_clock::now();
  std::string error;
  try {
    write_snapshot_file(snapshot);
    snapshot = SnapshotData{};  // the image's elements go now, not when the next snapshot starts
    rotate_journal(version, tail_from, records_before);
  } catch (const std::exception& e) {
    error = e.what();
  }
  {
    std::lock_guard<std::mutex> lock(mu_);
    running_ = false;
    if (error.empty())
      ++snapshots_;
    else
      attempt_at_ = records_;
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (error.empty()) SB_INFO(kLog, "snapshot at version " << version << " written in the background in " << ms << " ms");
  if (!error.empty())
    SB_ERROR(kLog, "the snapshot at version " << version << " could not be written in the background: " << error
                                              << "; the last snapshot and the journal after it stay in use");
  done_cv_.notify_all();
}

void Journal::rotate_journal(int64_t base_version, uint64_t tail_from, long records_before) {
  const std::string tmp = dir_ + "/journal.bin.tmp", path = dir_ + "/journal.bin";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0600);
  if (fd < 0) throw WmError(sys_error("cannot create " + tmp));
  // Only this thread renames the journal, so journal.bin is the file appended to.
  const int in = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  bool switched = false;
  try {
    if (in < 0) throw WmError(sys_error("cannot read " + path));
    const std::string header = journal_header(base_version);
    write_all(fd, header.data(), header.size(), tmp);
    uint64_t copied = tail_from;
    std::vector<uint8_t> buf(1 << 20);
    auto copy_to = [&](uint64_t end) {  // the complete records [copied, end) of the old journal
      while (copied < end) {
        const size_t n = static_cast<size_t>(std::min<uint64_t>(buf.size(), end - copied));
        const ssize_t r = ::pread(in, buf.data(), n, static_cast<off_t>(copied));
        if (r <= 0) throw WmError(sys_error("cannot read " + path));
        write_all(fd, buf.data(), static_cast<size_t>(r), tmp);
        copied += static_cast<uint64_t>(r);
      }
    };
    uint64_t end;
    {
      std::lock_guard<std::mutex> lock(mu_);
      end = size_;
    }
    copy_to(end);  // while commits go on
    if (::fsync(fd) != 0) throw WmError(sys_error("cannot sync " + tmp));
    if (test_hook) test_hook("journal");
    std::lock_guard<std::mutex> lock(mu_);  // no append from here to the directory's sync
    if (!broken_.empty()) throw WmError(broken_);
    if (size_ > copied) {  // the records appended meanwhile
      copy_to(size_);
      if (::fsync(fd) != 0) throw WmError(sys_error("cannot sync " + tmp));
    }
    if (::rename(tmp.c_str(), path.c_str()) != 0) throw WmError(sys_error("cannot rename " + tmp + " to " + path));
    switched = true;
    ::close(fd_);
    fd_ = fd;
    size_ = header.size() + (size_ - tail_from);
    records_ -= records_before;
    attempt_at_ = 0;
    try {
      sync_dir(dir_);
    } catch (const WmError& e) {
      // The new journal has its name, but perhaps not on disk: records appended to it
      // could vanish with the name. No more commits until a restart settles it.
      broken_ = std::string("the journal cannot be used: ") + e.what() + "; restart the server";
      throw WmError(broken_);
    }
  } catch (...) {
    if (in >= 0) ::close(in);
    if (!switched) {
      ::close(fd);
      ::unlink(tmp.c_str());  // the old journal goes on
    }
    throw;
  }
  ::close(in);
}

void Journal::fail(const std::string& why) {
  std::lock_guard<std::mutex> lock(mu_);
  if (broken_.empty()) broken_ = why;
}

bool Journal::snapshot_running() const {
  std::lock_guard<std::mutex> lock(mu_);
  return running_;
}

void Journal::wait_for_snapshot() {
  std::unique_lock<std::mutex> lock(mu_);
  done_cv_.wait(lock, [this] { return !running_; });
}

long Journal::records_since_snapshot() const {
  std::lock_guard<std::mutex> lock(mu_);
  return records_;
}

bool Journal::snapshot_due(long every) const {
  std::lock_guard<std::mutex> lock(mu_);
  return !running_ && records_ - attempt_at_ >= every;
}

long Journal::snapshots_written() const {
  std::lock_guard<std::mutex> lock(mu_);
  return snapshots_;
}

void write_file_durably(const std::string& dir, const std::string& name, const std::string& bytes) {
  replace_file_durably(dir, name, bytes);
}

RepairResult repair_data_dir(const std::string& dir) {
  const std::string jpath = dir + "/journal.bin", spath = dir + "/snapshot.bin";
  try {
    struct stat st;
    if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) return {1, dir + " is not a directory"};
    const int lock = lock_dir(dir);
    struct Unlock {
      int fd;
      ~Unlock() { ::close(fd); }
    } unlock{lock};
    const bool has_snapshot = exists(spath), has_journal = exists(jpath);
    int64_t snap_version = 0;
    if (has_snapshot) {
      try {
        snap_version = SnapshotFile(spath).version();
      } catch (const DataError& e) {
        return {1, std::string("cannot repair: ") + e.what()};
      }
    }
    const std::string v = std::to_string(snap_version);
    if (!has_journal) {
      if (!has_snapshot) return {0, "nothing to repair: " + dir + " has no journal and no snapshot (a new data directory)"};
      replace_file_durably(dir, "journal.bin", journal_header(snap_version));
      return {0, jpath + " was missing next to " + spath + " (version " + v +
                     "): wrote an empty journal going on from version " + v + "; the commits after version " + v +
                     ", if there were any, are lost"};
    }
    const std::string bytes = read_all(jpath);
    const JournalScan s = scan_bytes(bytes);
    const std::string b = std::to_string(s.base_version);
    if (s.header_ok && !has_snapshot && s.base_version != 0)
      return {1, "cannot repair: " + spath + " is missing and " + jpath + " goes on from the snapshot at version " + b +
                     ": restore snapshot.bin from a backup, or move " + dir + " aside to start anew"};
    if (s.header_ok && has_snapshot && s.base_version > snap_version)
      return {1, "cannot repair: " + jpath + " goes on from version " + b + " but " + spath + " is at version " + v +
                     ": restore the snapshot of version " + b};
    const long k = static_cast<long>(s.txns.size());
    if (s.end != JournalScan::End::Corrupt) {
      std::string m = "nothing to repair: " + jpath + " is intact (" + plural(k, "record", "records") + " after version " +
                      b + ")";
      if (s.end == JournalScan::End::Torn)
        m += "; its torn last record at byte " + std::to_string(s.good_end) +
             " (never acknowledged) is cut off when the server starts";
      return {0, m};
    }
    const std::string kept = s.header_ok ? bytes.substr(0, s.good_end) : journal_header(snap_version);
    std::string aside = jpath + ".corrupt";
    for (int n = 2; exists(aside); ++n) aside = jpath + ".corrupt." + std::to_string(n);
    // The original keeps its bytes and gets a second name; then the good prefix replaces
    // it as journal.bin. A crash in between leaves journal.bin as it was.
    const std::string tmp = jpath + ".repair.tmp";
    write_file_synced(tmp, kept);
    if (::link(jpath.c_str(), aside.c_str()) != 0) {
      const std::string e = sys_error("cannot keep " + jpath + " as " + aside);
      ::unlink(tmp.c_str());
      throw WmError(e);
    }
    sync_dir(dir);
    if (::rename(tmp.c_str(), jpath.c_str()) != 0) throw WmError(sys_error("cannot rename " + tmp + " to " + jpath));
    sync_dir(dir);
    const int64_t base = s.header_ok ? s.base_version : snap_version;
    std::string m = jpath + " was corrupt at byte " + std::to_string(s.good_end) + ": " + s.why + "; kept " +
                    (k == 0 ? std::string("no record") : "the " + plural(k, "intact record", "intact records") +
                                                             " before it (" + versions(base + 1, base + k) + ")") +
                    " in a new journal.bin going on from version " + std::to_string(base) + "; dropped the " +
                    std::to_string(s.size - s.good_end) + " bytes from byte " + std::to_string(s.good_end) + " on";
    if (s.intact_after > 0)
      m += " (with " + plural(s.intact_after, "intact record", "intact records") + " after the damage, " +
           versions(s.after_first_version, s.after_last_version) + ")";
    m += "; the original is kept unchanged as " + aside;
    return {0, m};
  } catch (const WmError& e) {
    return {1, std::string("cannot repair: ") + e.what()};
  }
}

namespace {

constexpr const char* kSceneKinds[] = {"scene_imports", "scene_extra"};

std::string scene_file_name(const char* kind, int64_t version) {
  return version == 0 ? std::string(kind) + ".ttl" : std::string(kind) + "." + std::to_string(version) + ".ttl";
}

// The version of a scene file's name: KIND.ttl (0) or KIND.V.ttl; -1 for any other name.
int64_t scene_file_version(const std::string& name, const char* kind) {
  const std::string k = kind;
  if (name == k + ".ttl") return 0;
  if (name.size() <= k.size() + 5 || name.compare(0, k.size() + 1, k + ".") != 0 ||
      name.compare(name.size() - 4, 4, ".ttl") != 0)
    return -1;
  const std::string digits = name.substr(k.size() + 1, name.size() - k.size() - 5);
  if (digits.empty() || digits.size() > 18 || digits[0] == '0' ||
      digits.find_first_not_of("0123456789") != std::string::npos)
    return -1;
  return std::stoll(digits);
}

// A generation's file, "" when it is missing (a write of the pair cut short before the second).
std::string read_scene_file(const std::string& path) { return exists(path) ? read_all(path) : ""; }

void remove_file(const std::string& path) {
  if (::unlink(path.c_str()) != 0 && errno != ENOENT) throw WmError(sys_error("cannot remove " + path));
}

// The versions of the generations on disk, and the leftovers of writes cut short.
struct SceneGenerations {
  std::vector<int64_t> versions;
  std::vector<std::string> leftovers;
};

SceneGenerations scene_generations(const std::string& dir) {
  SceneGenerations g;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    for (const char* kind : kSceneKinds) {
      const std::string k = kind;
      if (name.compare(0, k.size(), k) != 0) continue;
      if (name.size() > 8 && name.compare(name.size() - 8, 8, ".ttl.tmp") == 0) {  // replace_file_durably's
        g.leftovers.push_back(name);
        continue;
      }
      const int64_t v = scene_file_version(name, kind);
      if (v >= 0 && std::find(g.versions.begin(), g.versions.end(), v) == g.versions.end()) g.versions.push_back(v);
    }
  }
  if (ec) throw WmError("cannot list " + dir + ": " + ec.message());
  return g;
}

}  // namespace

void Journal::write_scene_files(int64_t version, const std::string& imports, const std::string& extra) {
  // A scene without such triples needs no files, unless they must replace an older generation.
  if (imports.empty() && extra.empty() && scene_generations(dir_).versions.empty()) return;
  replace_file_durably(dir_, scene_file_name("scene_imports", version), imports);
  replace_file_durably(dir_, scene_file_name("scene_extra", version), extra);
}

void Journal::remove_scene_files(int64_t version) {
  for (const char* kind : kSceneKinds) remove_file(dir_ + "/" + scene_file_name(kind, version));
  sync_dir(dir_);
}

Journal::SceneFiles Journal::settle_scene_files(int64_t snapshot_version) {
  const SceneGenerations g = scene_generations(dir_);
  const std::vector<int64_t>& versions = g.versions;
  const std::vector<std::string>& leftovers = g.leftovers;
  SceneFiles out;
  bool found = false;
  for (int64_t v : versions)
    if (v <= snapshot_version && (!found || v > out.version)) {
      out.version = v;
      found = true;
    }
  if (found) {
    out.imports_path = dir_ + "/" + scene_file_name("scene_imports", out.version);
    out.extra_path = dir_ + "/" + scene_file_name("scene_extra", out.version);
    out.imports = read_scene_file(out.imports_path);
    out.extra = read_scene_file(out.extra_path);
  }
  // Once the generations before it are gone, an empty generation in force says what no
  // files say.
  const bool empty_in_force = found && out.imports.empty() && out.extra.empty();
  bool removed = false;
  for (int64_t v : versions)
    if (!found || v != out.version || empty_in_force) {
      if (v > snapshot_version)
        SB_WARN(kLog, "removed the scene files of version " << v << " in " << dir_
                                                              << ": a scene change whose snapshot was never written");
      for (const char* kind : kSceneKinds) remove_file(dir_ + "/" + scene_file_name(kind, v));
      removed = true;
    }
  for (const auto& name : leftovers) {
    remove_file(dir_ + "/" + name);
    removed = true;
  }
  if (removed) sync_dir(dir_);
  return out;
}

}  // namespace skillbus::wm

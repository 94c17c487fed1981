#include "skillbus/wm/journal.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

#include "skillbus/bus.hpp"
#include "skillbus/wm/model.hpp"

namespace skillbus::wm {

namespace {

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

uint32_t get_u32(const uint8_t* b) { return b[0] | (b[1] << 8) | (b[2] << 16) | (uint32_t(b[3]) << 24); }

uint32_t crc(const uint8_t* d, size_t n) { return static_cast<uint32_t>(crc32(0L, d, static_cast<uInt>(n))); }

void sync_dir(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

Journal::Journal(std::string dir) : dir_(std::move(dir)) {
  if (::mkdir(dir_.c_str(), 0755) != 0 && errno != EEXIST) throw WmError(sys_error("cannot create data directory " + dir_));
}

Journal::~Journal() {
  if (fd_ >= 0) ::close(fd_);
}

void Journal::open_journal(bool truncate) {
  if (fd_ >= 0) ::close(fd_);
  const std::string path = dir_ + "/journal.bin";
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | (truncate ? O_TRUNC : 0), 0644);
  if (fd_ < 0) throw WmError(sys_error("cannot open " + path));
  if (truncate) {
    ::fdatasync(fd_);
    sync_dir(dir_);
  }
}

Journal::Recovered Journal::recover() {
  Recovered out;
  {
    std::ifstream f(dir_ + "/snapshot.bin", std::ios::binary);
    if (f) {
      const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
      skillbus_msgs::wm_snapshot_t snap;
      if (!decode_msg(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), snap))
        throw WmError("snapshot " + dir_ + "/snapshot.bin is corrupt; refusing to start without it");
      out.snapshot = std::move(snap);
    }
  }
  const std::string path = dir_ + "/journal.bin";
  std::ifstream f(path, std::ios::binary);
  std::string bytes;
  if (f) bytes.assign((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const auto* b = reinterpret_cast<const uint8_t*>(bytes.data());
  size_t pos = 0;
  while (pos < bytes.size()) {
    if (bytes.size() - pos < 8) break;
    const uint32_t len = get_u32(b + pos), sum = get_u32(b + pos + 4);
    if (len > bytes.size() - pos - 8 || crc(b + pos + 8, len) != sum) break;
    skillbus_msgs::wm_txn_t txn;
    if (!decode_msg(b + pos + 8, len, txn)) break;
    out.txns.push_back(std::move(txn));
    pos += 8 + len;
  }
  if (pos < bytes.size()) {
    out.note = "cut off a torn journal record at byte " + std::to_string(pos) + " (" +
               std::to_string(bytes.size() - pos) + " bytes, never acknowledged)";
    if (::truncate(path.c_str(), static_cast<off_t>(pos)) != 0) throw WmError(sys_error("cannot truncate " + path));
  }
  records_ = static_cast<long>(out.txns.size());
  open_journal(false);
  return out;
}

void Journal::append(const skillbus_msgs::wm_txn_t& txn) {
  if (fd_ < 0) open_journal(false);
  const Bytes body = encode_msg(txn);
  Bytes rec(8 + body.size());
  put_u32(rec.data(), static_cast<uint32_t>(body.size()));
  put_u32(rec.data() + 4, crc(body.data(), body.size()));
  std::copy(body.begin(), body.end(), rec.begin() + 8);
  write_all(fd_, rec.data(), rec.size(), dir_ + "/journal.bin");  // one write: O_APPEND keeps it whole
  if (::fdatasync(fd_) != 0) throw WmError(sys_error("cannot sync " + dir_ + "/journal.bin"));
  ++records_;
}

void Journal::write_snapshot(const skillbus_msgs::wm_snapshot_t& snapshot) {
  const std::string tmp = dir_ + "/snapshot.bin.tmp", path = dir_ + "/snapshot.bin";
  const Bytes bytes = encode_msg(snapshot);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw WmError(sys_error("cannot create " + tmp));
  try {
    write_all(fd, bytes.data(), bytes.size(), tmp);
    if (::fsync(fd) != 0) throw WmError(sys_error("cannot sync " + tmp));
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path.c_str()) != 0) throw WmError(sys_error("cannot rename " + tmp));
  sync_dir(dir_);
  // Records up to the snapshot's version are in it now. A crash before this truncation
  // leaves them in the journal too; recovery skips records older than the snapshot.
  open_journal(true);
  records_ = 0;
}

}  // namespace skillbus::wm

/* What a power loss would keep: an LD_PRELOAD shim that records what a process has made
 * durable in one directory, so a test can rebuild the directory as a power loss at that
 * moment could leave it (tests/integration/journal_fault_driver.py).
 *
 * The model is POSIX's strictest reading: a file's bytes are on disk up to the length it
 * had at its last fsync/fdatasync, and a directory holds the names it had at its last
 * fsync. So the shim, in fsync() and fdatasync() of
 *   a regular file in $SB_FSYNC_DIR: hard-links the file as $SB_FSYNC_SHADOW/<inode> (so
 *       its bytes outlive a rename over it) and, once the real call succeeded, appends
 *       "F <inode> <size at the call>" to $SB_FSYNC_LOG;
 *   the directory $SB_FSYNC_DIR itself: appends "D name:inode name:inode ..." (its entries
 *       when the real call succeeded).
 * With $SB_FSYNC_DELAY_US, each of those syncs takes that much longer (a slow disk), so that
 * a kill at a random moment often finds written but unsynced data.
 * Everything else passes through. Build: cc -shared -fPIC -O2 -o fsync_shim.so fsync_shim.c -ldl
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char watched[PATH_MAX];
static const char* shadow;
static const char* logpath;
static int ready = -1; /* -1 not yet looked, 0 off, 1 on */
static useconds_t delay_us;

static void setup(void) {
  if (ready >= 0) return;
  const char* dir = getenv("SB_FSYNC_DIR");
  shadow = getenv("SB_FSYNC_SHADOW");
  logpath = getenv("SB_FSYNC_LOG");
  const char* delay = getenv("SB_FSYNC_DELAY_US");
  delay_us = delay ? (useconds_t)atoi(delay) : 0;
  ready = dir && shadow && logpath && realpath(dir, watched) != NULL;
}

static void log_line(const char* line, size_t n) {
  const int fd = open(logpath, O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) return;
  if (write(fd, line, n) != (ssize_t)n) { /* the test sees a missing line as unsynced data */
  }
  close(fd);
}

/* 0: not ours; 1: a file in the directory; 2: the directory. */
static int classify(int fd, struct stat* st) {
  setup();
  if (ready != 1 || fstat(fd, st) != 0) return 0;
  char proc[64], path[PATH_MAX];
  snprintf(proc, sizeof proc, "/proc/self/fd/%d", fd);
  const ssize_t n = readlink(proc, path, sizeof path - 1);
  if (n <= 0) return 0;
  path[n] = 0;
  if (S_ISDIR(st->st_mode)) return strcmp(path, watched) == 0 ? 2 : 0;
  if (!S_ISREG(st->st_mode)) return 0;
  const size_t w = strlen(watched);
  if (strncmp(path, watched, w) != 0 || path[w] != '/' || strchr(path + w + 1, '/') != NULL) return 0;
  if (strstr(path, " (deleted)") != NULL) return 1; /* linked at an earlier sync */
  char target[PATH_MAX];
  snprintf(target, sizeof target, "%s/%lu", shadow, (unsigned long)st->st_ino);
  link(path, target); /* EEXIST after the first sync of this inode */
  return 1;
}

static void record(int kind, int fd, const struct stat* st) {
  char line[8192];
  size_t n;
  if (kind == 1) {
    n = (size_t)snprintf(line, sizeof line, "F %lu %lld\n", (unsigned long)st->st_ino, (long long)st->st_size);
  } else {
    DIR* d = opendir(watched);
    if (!d) return;
    n = (size_t)snprintf(line, sizeof line, "D");
    struct dirent* e;
    while ((e = readdir(d)) != NULL && n < sizeof line - 300) {
      if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
      n += (size_t)snprintf(line + n, sizeof line - n, " %s:%lu", e->d_name, (unsigned long)e->d_ino);
    }
    closedir(d);
    line[n++] = '\n';
  }
  (void)fd;
  log_line(line, n);
}

typedef int (*sync_fn)(int);

static int wrapped(const char* name, sync_fn* real, int fd) {
  if (!*real) *real = (sync_fn)dlsym(RTLD_NEXT, name);
  struct stat st;
  const int kind = classify(fd, &st);
  if (kind && delay_us) usleep(delay_us);
  const int r = (*real)(fd);
  if (r == 0 && kind) {
    const int e = errno;
    record(kind, fd, &st);
    errno = e;
  }
  return r;
}

int fsync(int fd) {
  static sync_fn real;
  return wrapped("fsync", &real, fd);
}

int fdatasync(int fd) {
  static sync_fn real;
  return wrapped("fdatasync", &real, fd);
}

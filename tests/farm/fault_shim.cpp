// Preloaded into a real tessera-server (LD_PRELOAD) by the fault-injection test: fails one
// kind of call, from a chosen point of the run on, a chosen number of times, then lets
// them through again, as a disk that fills and is freed, a descriptor table that runs
// out, or a SQLite call that fails. Every fault it injects is a line in a log file, which
// the test counts. The product has no hook for it: the calls are the real ones, taken
// over by the dynamic linker.
//
//   TESSERA_FAULT        sqlite_prepare | sqlite_step | sqlite_release | sqlite_checkpoint |
//                        write_enospc | write_eio | open_emfile
//   TESSERA_FAULT_AFTER  matching calls let through before the first fault
//   TESSERA_FAULT_COUNT  faults in a row, then none
//   TESSERA_FAULT_PATH   file faults only for paths under this one (the data dir)
//   TESSERA_FAULT_LOG    where each fault is written as a line
//   TESSERA_FAULT_ARM    nothing counts until this file exists (the coordinator's own
//                        start-up is not what the test is about)
//   TESSERA_FAULT_TALLY  where the count of matching calls is written at a clean exit: how
//                        the test's ranges of first faults were chosen
#include <dlfcn.h>
#include <fcntl.h>
#include <sys/syscall.h>
#include <sys/uio.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <sqlite3.h>

namespace {

enum class Kind {
  none,
  sqlite_prepare,
  sqlite_step,
  sqlite_release,
  sqlite_checkpoint,
  write_enospc,
  write_eio,
  open_emfile
};

struct Config {
  Kind kind = Kind::none;
  std::atomic<long> after{0};
  std::atomic<long> count{0};
  char path[4096] = {};
  std::size_t path_length = 0;
  char log[4096] = {};
  char arm[4096] = {};
  std::atomic<bool> armed{false};
  std::atomic<long> matching{0};
  char tally[4096] = {};
};

Config& config() {
  static Config* const instance = [] {
    auto* c = new Config;  // never freed: used until the process's last call
    const char* kind = std::getenv("TESSERA_FAULT");
    const struct {
      const char* name;
      Kind kind;
    } kinds[] = {
        {"sqlite_prepare", Kind::sqlite_prepare}, {"sqlite_step", Kind::sqlite_step},
        {"sqlite_release", Kind::sqlite_release}, {"sqlite_checkpoint", Kind::sqlite_checkpoint},
        {"write_enospc", Kind::write_enospc},     {"write_eio", Kind::write_eio},
        {"open_emfile", Kind::open_emfile}};
    for (const auto& k : kinds)
      if (kind && std::strcmp(kind, k.name) == 0) c->kind = k.kind;
    if (const char* after = std::getenv("TESSERA_FAULT_AFTER")) c->after = std::atol(after);
    if (const char* count = std::getenv("TESSERA_FAULT_COUNT")) c->count = std::atol(count);
    if (const char* path = std::getenv("TESSERA_FAULT_PATH")) {
      std::snprintf(c->path, sizeof c->path, "%s", path);
      c->path_length = std::strlen(c->path);
    }
    if (const char* log = std::getenv("TESSERA_FAULT_LOG"))
      std::snprintf(c->log, sizeof c->log, "%s", log);
    if (const char* tally = std::getenv("TESSERA_FAULT_TALLY"))
      std::snprintf(c->tally, sizeof c->tally, "%s", tally);
    if (const char* arm = std::getenv("TESSERA_FAULT_ARM"))
      std::snprintf(c->arm, sizeof c->arm, "%s", arm);
    else
      c->armed = true;
    return c;
  }();
  return *instance;
}

// Whether this matching call fails: after `after` have passed, `count` of them do.
bool inject(Kind kind, const char* what) {
  Config& c = config();
  if (c.kind != kind) return false;
  if (!c.armed) {
    // A raw system call: the interposed ones would come back here.
    if (::syscall(SYS_faccessat, AT_FDCWD, c.arm, F_OK, 0) != 0) return false;
    c.armed = true;
  }
  c.matching.fetch_add(1);
  if (c.after.fetch_sub(1) > 0) return false;
  if (c.count.fetch_sub(1) <= 0) return false;
  if (c.log[0]) {
    // Raw system calls: the interposed ones below would count themselves.
    const int fd = static_cast<int>(
        ::syscall(SYS_openat, AT_FDCWD, c.log, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644));
    if (fd >= 0) {
      char line[256];
      const int n = std::snprintf(line, sizeof line, "%s\n", what);
      ::syscall(SYS_write, fd, line, static_cast<std::size_t>(n));
      ::syscall(SYS_close, fd);
    }
  }
  return true;
}

struct Tally {
  ~Tally() {
    const Config& c = config();
    if (!c.tally[0]) return;
    if (FILE* out = std::fopen(c.tally, "w")) {
      std::fprintf(out, "%ld\n", c.matching.load());
      std::fclose(out);
    }
  }
} tally_at_exit;

// Descriptors opened on a path under TESSERA_FAULT_PATH.
constexpr int kMaxFd = 1 << 16;
std::atomic<bool> watched[kMaxFd];

bool under_path(const char* path) {
  const Config& c = config();
  return c.path_length > 0 && path && std::strncmp(path, c.path, c.path_length) == 0;
}
void note_open(int fd, const char* path) {
  if (fd >= 0 && fd < kMaxFd) watched[fd] = under_path(path);
}
bool is_watched(int fd) { return fd >= 0 && fd < kMaxFd && watched[fd].load(); }

template <class F>
F real(const char* name) {
  return reinterpret_cast<F>(::dlsym(RTLD_NEXT, name));
}

// A write to a watched file that fails as a full or broken disk does.
bool write_fails(int fd) {
  if (!is_watched(fd)) return false;
  if (inject(Kind::write_enospc, "write ENOSPC")) {
    errno = ENOSPC;
    return true;
  }
  if (inject(Kind::write_eio, "write EIO")) {
    errno = EIO;
    return true;
  }
  return false;
}

int open_common(const char* path, int fd_if_ok) {
  note_open(fd_if_ok, path);
  return fd_if_ok;
}

bool open_fails(const char* path) {
  if (!under_path(path) || !inject(Kind::open_emfile, "open EMFILE")) return false;
  errno = EMFILE;
  return true;
}

mode_t mode_of(int flags, va_list args) {
  return (flags & O_CREAT) || (flags & O_TMPFILE) == O_TMPFILE ? va_arg(args, mode_t) : 0;
}

}  // namespace

extern "C" {

int open(const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_of(flags, args);
  va_end(args);
  if (open_fails(path)) return -1;
  static const auto next = real<int (*)(const char*, int, ...)>("open");
  return open_common(path, next(path, flags, mode));
}

int open64(const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_of(flags, args);
  va_end(args);
  if (open_fails(path)) return -1;
  static const auto next = real<int (*)(const char*, int, ...)>("open64");
  return open_common(path, next(path, flags, mode));
}

int openat(int dir, const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_of(flags, args);
  va_end(args);
  if (open_fails(path)) return -1;
  static const auto next = real<int (*)(int, const char*, int, ...)>("openat");
  return open_common(path, next(dir, path, flags, mode));
}

int openat64(int dir, const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_of(flags, args);
  va_end(args);
  if (open_fails(path)) return -1;
  static const auto next = real<int (*)(int, const char*, int, ...)>("openat64");
  return open_common(path, next(dir, path, flags, mode));
}

int close(int fd) {
  if (fd >= 0 && fd < kMaxFd) watched[fd] = false;
  static const auto next = real<int (*)(int)>("close");
  return next(fd);
}

ssize_t write(int fd, const void* data, size_t size) {
  if (write_fails(fd)) return -1;
  static const auto next = real<ssize_t (*)(int, const void*, size_t)>("write");
  return next(fd, data, size);
}

ssize_t pwrite(int fd, const void* data, size_t size, off_t at) {
  if (write_fails(fd)) return -1;
  static const auto next = real<ssize_t (*)(int, const void*, size_t, off_t)>("pwrite");
  return next(fd, data, size, at);
}

ssize_t pwrite64(int fd, const void* data, size_t size, off64_t at) {
  if (write_fails(fd)) return -1;
  static const auto next = real<ssize_t (*)(int, const void*, size_t, off64_t)>("pwrite64");
  return next(fd, data, size, at);
}

ssize_t writev(int fd, const struct iovec* parts, int count) {
  if (write_fails(fd)) return -1;
  static const auto next = real<ssize_t (*)(int, const struct iovec*, int)>("writev");
  return next(fd, parts, count);
}

ssize_t pwritev(int fd, const struct iovec* parts, int count, off_t at) {
  if (write_fails(fd)) return -1;
  static const auto next = real<ssize_t (*)(int, const struct iovec*, int, off_t)>("pwritev");
  return next(fd, parts, count, at);
}

ssize_t pwritev64(int fd, const struct iovec* parts, int count, off64_t at) {
  if (write_fails(fd)) return -1;
  static const auto next = real<ssize_t (*)(int, const struct iovec*, int, off64_t)>("pwritev64");
  return next(fd, parts, count, at);
}

int sqlite3_prepare_v3(sqlite3* db, const char* sql, int bytes, unsigned int flags,
                       sqlite3_stmt** statement, const char** tail) {
  if (inject(Kind::sqlite_prepare, "sqlite3_prepare_v3")) {
    *statement = nullptr;
    return SQLITE_IOERR;
  }
  static const auto next =
      real<int (*)(sqlite3*, const char*, int, unsigned int, sqlite3_stmt**, const char**)>(
          "sqlite3_prepare_v3");
  return next(db, sql, bytes, flags, statement, tail);
}

int sqlite3_step(sqlite3_stmt* statement) {
  const char* sql = statement ? sqlite3_sql(statement) : nullptr;
  const bool release = sql && std::strncmp(sql, "RELEASE", 7) == 0;
  if (release ? inject(Kind::sqlite_release, "sqlite3_step RELEASE")
              : inject(Kind::sqlite_step, "sqlite3_step"))
    return release ? SQLITE_FULL : SQLITE_IOERR;
  static const auto next = real<int (*)(sqlite3_stmt*)>("sqlite3_step");
  return next(statement);
}

int sqlite3_wal_checkpoint_v2(sqlite3* db, const char* name, int mode, int* log, int* done) {
  if (inject(Kind::sqlite_checkpoint, "sqlite3_wal_checkpoint_v2")) return SQLITE_IOERR;
  static const auto next =
      real<int (*)(sqlite3*, const char*, int, int*, int*)>("sqlite3_wal_checkpoint_v2");
  return next(db, name, mode, log, done);
}

}  // extern "C"

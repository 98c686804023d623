// A SQLite VFS over the system's that fails file operations on demand, as a full or
// failing disk does: every connection opened while it is installed goes through it. For
// the store's tests of what a failed write leaves behind, with no root and no small disk.
#pragma once

#include <atomic>
#include <cstring>
#include <stdexcept>

#include <sqlite3.h>

namespace tessera::test {

class FaultyVfs {
 public:
  // Which operations fail once armed.
  enum class Fails { nothing, writes, syncs, opens };

  // Installs itself as the default VFS; uninstalls itself when destroyed.
  FaultyVfs() {
    real_ = sqlite3_vfs_find(nullptr);
    if (!real_) throw std::runtime_error("no default SQLite VFS");
    std::memset(&vfs_, 0, sizeof vfs_);
    vfs_ = *real_;  // every method the system's, but for opening a file
    vfs_.zName = "tessera-faulty";
    vfs_.szOsFile = static_cast<int>(sizeof(File)) + real_->szOsFile;
    vfs_.pAppData = this;
    vfs_.xOpen = &FaultyVfs::open;
    if (sqlite3_vfs_register(&vfs_, 1) != SQLITE_OK)
      throw std::runtime_error("cannot register the faulty SQLite VFS");
    methods_ = {};
  }
  ~FaultyVfs() { sqlite3_vfs_unregister(&vfs_); }
  FaultyVfs(const FaultyVfs&) = delete;
  FaultyVfs& operator=(const FaultyVfs&) = delete;

  // From the `after`-th matching operation on (0: the next one), each fails with `code`
  // (SQLITE_FULL, SQLITE_IOERR_WRITE, ...) until disarm().
  void arm(Fails what, int code, int after = 0) {
    code_ = code;
    countdown_ = after;
    fails_ = what;
  }
  void disarm() { fails_ = Fails::nothing; }
  // Operations failed so far.
  int failed() const { return failed_; }

 private:
  struct File {
    sqlite3_file base;
    FaultyVfs* owner;
    sqlite3_file* real;  // right after this struct, szOsFile bytes of the system's file
  };

  bool fail_now(Fails what) {
    if (fails_ != what) return false;
    if (countdown_ > 0) {
      --countdown_;
      return false;
    }
    ++failed_;
    return true;
  }

  static File& file(sqlite3_file* f) { return *reinterpret_cast<File*>(f); }
  static sqlite3_file* real(sqlite3_file* f) { return file(f).real; }

  static int open(sqlite3_vfs* vfs, const char* name, sqlite3_file* f, int flags, int* out) {
    auto& self = *static_cast<FaultyVfs*>(vfs->pAppData);
    File& wrapper = file(f);
    wrapper.owner = &self;
    wrapper.real = reinterpret_cast<sqlite3_file*>(&wrapper + 1);
    wrapper.base.pMethods = nullptr;
    if (self.fail_now(Fails::opens)) return SQLITE_CANTOPEN;
    const int rc = self.real_->xOpen(self.real_, name, wrapper.real, flags, out);
    if (rc != SQLITE_OK || !wrapper.real->pMethods) return rc;
    self.wrap(wrapper.real->pMethods);
    wrapper.base.pMethods = &self.methods_;
    return SQLITE_OK;
  }

  // The methods are the system file's, but writes, truncations and syncs may fail.
  void wrap(const sqlite3_io_methods* system) {
    if (methods_.iVersion != 0) return;
    system_ = system;
    methods_ = *system;
    methods_.xClose = [](sqlite3_file* f) {
      const int rc = real(f)->pMethods->xClose(real(f));
      f->pMethods = nullptr;
      return rc;
    };
    methods_.xRead = [](sqlite3_file* f, void* data, int amount, sqlite3_int64 offset) {
      return real(f)->pMethods->xRead(real(f), data, amount, offset);
    };
    methods_.xWrite = [](sqlite3_file* f, const void* data, int amount, sqlite3_int64 offset) {
      if (file(f).owner->fail_now(Fails::writes)) return file(f).owner->code_.load();
      return real(f)->pMethods->xWrite(real(f), data, amount, offset);
    };
    methods_.xTruncate = [](sqlite3_file* f, sqlite3_int64 size) {
      return real(f)->pMethods->xTruncate(real(f), size);
    };
    methods_.xSync = [](sqlite3_file* f, int flags) {
      if (file(f).owner->fail_now(Fails::syncs)) return file(f).owner->code_.load();
      return real(f)->pMethods->xSync(real(f), flags);
    };
    methods_.xFileSize = [](sqlite3_file* f, sqlite3_int64* size) {
      return real(f)->pMethods->xFileSize(real(f), size);
    };
    methods_.xLock = [](sqlite3_file* f, int level) {
      return real(f)->pMethods->xLock(real(f), level);
    };
    methods_.xUnlock = [](sqlite3_file* f, int level) {
      return real(f)->pMethods->xUnlock(real(f), level);
    };
    methods_.xCheckReservedLock = [](sqlite3_file* f, int* out) {
      return real(f)->pMethods->xCheckReservedLock(real(f), out);
    };
    methods_.xFileControl = [](sqlite3_file* f, int op, void* arg) {
      return real(f)->pMethods->xFileControl(real(f), op, arg);
    };
    methods_.xSectorSize = [](sqlite3_file* f) { return real(f)->pMethods->xSectorSize(real(f)); };
    methods_.xDeviceCharacteristics = [](sqlite3_file* f) {
      return real(f)->pMethods->xDeviceCharacteristics(real(f));
    };
    methods_.xShmMap = [](sqlite3_file* f, int page, int size, int extend, void volatile** out) {
      return real(f)->pMethods->xShmMap(real(f), page, size, extend, out);
    };
    methods_.xShmLock = [](sqlite3_file* f, int offset, int n, int flags) {
      return real(f)->pMethods->xShmLock(real(f), offset, n, flags);
    };
    methods_.xShmBarrier = [](sqlite3_file* f) { real(f)->pMethods->xShmBarrier(real(f)); };
    methods_.xShmUnmap = [](sqlite3_file* f, int remove) {
      return real(f)->pMethods->xShmUnmap(real(f), remove);
    };
    methods_.xFetch = [](sqlite3_file* f, sqlite3_int64 offset, int amount, void** out) {
      return real(f)->pMethods->xFetch(real(f), offset, amount, out);
    };
    methods_.xUnfetch = [](sqlite3_file* f, sqlite3_int64 offset, void* data) {
      return real(f)->pMethods->xUnfetch(real(f), offset, data);
    };
  }

  sqlite3_vfs vfs_{};
  sqlite3_vfs* real_ = nullptr;
  const sqlite3_io_methods* system_ = nullptr;
  sqlite3_io_methods methods_{};
  std::atomic<Fails> fails_{Fails::nothing};
  std::atomic<int> code_{SQLITE_FULL};
  std::atomic<int> countdown_{0};
  std::atomic<int> failed_{0};
};

}  // namespace tessera::test

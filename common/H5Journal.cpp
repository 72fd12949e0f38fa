#include "common/H5Journal.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include "common/FaultInjection.h"
#include "common/Hdf5.h"
#include "common/Strings.h"

namespace granagg::common::h5journal {
static_assert(std::is_same<hid_t, std::int64_t>::value, "H5Journal.h hands hid_t as int64_t");

namespace {

// Journal layout (native byte order; a journal is only ever read on the machine that wrote it):
//   header  magic[8] | committed size u64 | checksum u64 (of the first 16 bytes)
//   entry   address u64 | length u64 | length bytes | checksum u64 (of address, length, bytes)
constexpr char MAGIC[8] = {'G', 'R', 'N', 'G', 'J', 'N', 'L', '1'};
constexpr std::size_t HEADER_SIZE = 24;
constexpr std::size_t ENTRY_OVERHEAD = 24;
constexpr haddr_t MAX_ADDR = (static_cast<haddr_t>(1) << (8 * sizeof(off_t) - 1)) - 1;

/// FNV-1a, 64 bit: detects an entry cut short by a kill (not an adversary).
std::uint64_t fnv1a(const void* data, std::size_t n, std::uint64_t h = 14695981039346656037ULL) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ULL;
  }
  return h;
}

bool writeAll(int fd, const void* data, std::size_t n, off_t at) {
  const auto* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::pwrite(fd, p, n, at);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= static_cast<std::size_t>(w);
    at += w;
  }
  return true;
}

/// Reads up to n bytes at `at`; returns the count read (short at the end of the file), -1 on error.
ssize_t readAll(int fd, void* data, std::size_t n, off_t at) {
  auto* p = static_cast<char*>(data);
  std::size_t got = 0;
  while (got < n) {
    const ssize_t r = ::pread(fd, p + got, n - got, at + static_cast<off_t>(got));
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) return -1;
    if (r == 0) break;
    got += static_cast<std::size_t>(r);
  }
  return static_cast<ssize_t>(got);
}

void pushError(H5E_minor_t minor, const std::string& msg) {
  H5Epush2(H5E_DEFAULT, __FILE__, "h5journal", __LINE__, H5E_ERR_CLS, H5E_VFL, minor, "%s",
           msg.c_str());
}

/// The committed size an intact journal header records; false for no journal or a torn header.
bool readHeader(int jfd, std::uint64_t& committed) {
  unsigned char h[HEADER_SIZE];
  if (readAll(jfd, h, HEADER_SIZE, 0) != static_cast<ssize_t>(HEADER_SIZE)) return false;
  if (std::memcmp(h, MAGIC, sizeof MAGIC) != 0) return false;
  std::uint64_t sum;
  std::memcpy(&committed, h + 8, 8);
  std::memcpy(&sum, h + 16, 8);
  return sum == fnv1a(h, 16);
}

struct Entry {
  std::uint64_t address;
  std::vector<unsigned char> bytes;
};

/// The complete entries after the header; a torn last entry (the kill came while it was being
/// appended, so before the write it protects) is left out.
std::vector<Entry> readEntries(int jfd) {
  std::vector<Entry> entries;
  off_t at = HEADER_SIZE;
  for (;;) {
    std::uint64_t head[2];
    if (readAll(jfd, head, sizeof head, at) != static_cast<ssize_t>(sizeof head)) break;
    struct stat st;
    if (::fstat(jfd, &st) != 0 || head[1] > static_cast<std::uint64_t>(st.st_size)) break;
    Entry e{head[0], std::vector<unsigned char>(head[1])};
    if (readAll(jfd, e.bytes.data(), e.bytes.size(), at + 16) !=
        static_cast<ssize_t>(e.bytes.size()))
      break;
    std::uint64_t sum;
    if (readAll(jfd, &sum, 8, at + 16 + static_cast<off_t>(head[1])) != 8) break;
    if (sum != fnv1a(e.bytes.data(), e.bytes.size(), fnv1a(head, sizeof head))) break;
    at += static_cast<off_t>(ENTRY_OVERHEAD + head[1]);
    entries.push_back(std::move(e));
  }
  return entries;
}

/// The driver's file: HDF5's public part first, as the virtual file layer requires.
struct JournaledFile {
  H5FD_t pub;
  int fd = -1;
  int jfd = -1;  // the journal, opened at the first overwrite
  bool writable = false;
  // A write failed since the last commit: the file may be torn, and it stays frozen at that
  // commit. Later writes are dropped (reported as done, so that HDF5 can still close the file
  // cleanly: a close that fails leaves HDF5 a half-closed file that it crashes on at exit),
  // commits are refused, and the journal is kept for recover().
  bool failed = false;
  std::string failure;  // the first failed write's message (what writeFailure returns)
  bool in_txn = false;    // the journal holds this transaction's header
  off_t journal_end = 0;  // where the next entry goes
  haddr_t eoa = 0, eof = 0;
  haddr_t committed = 0;  // file size at the last commit
  dev_t device = 0;
  ino_t inode = 0;
  std::string path, journal;

  void fail(const std::string& why) {
    if (!failed) failure = why;
    failed = true;
  }

  bool openJournal() {
    if (jfd >= 0) return true;
    jfd = ::open(journal.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    return jfd >= 0;
  }

  /// Saves the committed bytes in [addr, addr + size) before they are overwritten or cut off.
  bool journalRegion(haddr_t addr, haddr_t size) {
    const haddr_t end = std::min<haddr_t>({addr + size, committed, eof});
    if (addr >= end) return true;
    if (!openJournal()) return false;
    if (!in_txn) {
      unsigned char h[HEADER_SIZE];
      std::memcpy(h, MAGIC, sizeof MAGIC);
      const std::uint64_t c = committed;
      std::memcpy(h + 8, &c, 8);
      const std::uint64_t sum = fnv1a(h, 16);
      std::memcpy(h + 16, &sum, 8);
      if (::ftruncate(jfd, 0) != 0 || !writeAll(jfd, h, HEADER_SIZE, 0)) return false;
      in_txn = true;
      journal_end = HEADER_SIZE;
    }
    const std::uint64_t head[2] = {addr, end - addr};
    std::vector<unsigned char> rec(ENTRY_OVERHEAD + head[1]);
    std::memcpy(rec.data(), head, sizeof head);
    if (readAll(fd, rec.data() + 16, head[1], static_cast<off_t>(addr)) !=
        static_cast<ssize_t>(head[1]))
      return false;
    const std::uint64_t sum = fnv1a(rec.data() + 16, head[1], fnv1a(head, sizeof head));
    std::memcpy(rec.data() + 16 + head[1], &sum, 8);
    // One pwrite for the whole entry; a kill inside it leaves a torn entry that readEntries
    // drops, and the overwrite it protects has not been issued yet.
    if (!writeAll(jfd, rec.data(), rec.size(), journal_end)) return false;
    journal_end += static_cast<off_t>(rec.size());
    return true;
  }

  bool commitNow() {
    if (failed) {
      errno = EIO;
      return false;
    }
    struct stat st;
    if (::fstat(fd, &st) != 0) return false;
    if (in_txn) {
      if (::ftruncate(jfd, 0) != 0) return false;
      in_txn = false;
      journal_end = 0;
    }
    committed = static_cast<haddr_t>(st.st_size);
    eof = committed;
    failed = false;
    return true;
  }
};

JournaledFile* self(H5FD_t* f) { return reinterpret_cast<JournaledFile*>(f); }
const JournaledFile* self(const H5FD_t* f) { return reinterpret_cast<const JournaledFile*>(f); }

H5FD_t* jOpen(const char* name, unsigned flags, hid_t, haddr_t maxaddr) {
  if (!name || !*name || maxaddr == 0 || maxaddr == HADDR_UNDEF || maxaddr > MAX_ADDR) {
    pushError(H5E_BADVALUE, "h5journal: bad file name or address space");
    return nullptr;
  }
  const bool rw = (flags & H5F_ACC_RDWR) != 0;
  int o = rw ? O_RDWR : O_RDONLY;
  if (flags & H5F_ACC_TRUNC) o |= O_TRUNC;
  if (flags & H5F_ACC_CREAT) o |= O_CREAT;
  if (flags & H5F_ACC_EXCL) o |= O_EXCL;
  auto* f = new JournaledFile();
  f->path = name;
  f->journal = journalPathFor(name);
  f->writable = rw;
  const bool creating = (flags & (H5F_ACC_TRUNC | H5F_ACC_CREAT)) != 0;
  if (rw && !creating && pending(f->path)) {
    pushError(H5E_CANTOPENFILE, "'" + f->path + "' has an unfinished write in '" + f->journal +
                                    "' (a killed writer): recover it first");
    delete f;
    return nullptr;
  }
  // O_TRUNC only once the flock is held: never cut a file that a live writer has open
  f->fd = ::open(name, (o & ~O_TRUNC) | O_CLOEXEC, 0666);
  if (f->fd < 0) {
    pushError(H5E_CANTOPENFILE, "h5journal: cannot open '" + f->path + "': " +
                                    std::strerror(errno));
    delete f;
    return nullptr;
  }
  // The writer's flock: recover() and the readers take a live lock holder for a live writer.
  if (rw && ::flock(f->fd, LOCK_EX | LOCK_NB) != 0) {
    pushError(H5E_CANTLOCKFILE,
              "'" + f->path + "' is open for writing in another process (" +
                  std::strerror(errno) + ")");
    ::close(f->fd);
    delete f;
    return nullptr;
  }
  if ((o & O_TRUNC) && ::ftruncate(f->fd, 0) != 0) {
    pushError(H5E_CANTOPENFILE, "h5journal: cannot truncate '" + f->path + "'");
    ::close(f->fd);
    delete f;
    return nullptr;
  }
  if (rw && creating) ::unlink(f->journal.c_str());  // a new file: any old journal is moot
  struct stat st;
  if (::fstat(f->fd, &st) != 0) {
    pushError(H5E_CANTGET, "h5journal: cannot stat '" + f->path + "'");
    ::close(f->fd);
    delete f;
    return nullptr;
  }
  f->eof = f->committed = static_cast<haddr_t>(st.st_size);
  f->device = st.st_dev;
  f->inode = st.st_ino;
  return &f->pub;
}

herr_t jClose(H5FD_t* file) {
  JournaledFile* f = self(file);
  herr_t rc = 0;
  // HDF5 flushed everything before it closes the driver; unless a write failed on the way the
  // file is complete now, and the journal has nothing left to undo.
  if (f->writable && !f->failed) {
    if (f->jfd >= 0) ::close(f->jfd);
    f->jfd = -1;
    ::unlink(f->journal.c_str());
  }
  if (f->jfd >= 0) ::close(f->jfd);
  if (::close(f->fd) != 0) {
    pushError(H5E_CANTCLOSEFILE, "h5journal: close failed for '" + f->path + "'");
    rc = -1;
  }
  delete f;
  return rc;
}

int jCmp(const H5FD_t* a, const H5FD_t* b) {
  const JournaledFile *x = self(a), *y = self(b);
  if (x->device != y->device) return x->device < y->device ? -1 : 1;
  if (x->inode != y->inode) return x->inode < y->inode ? -1 : 1;
  return 0;
}

herr_t jQuery(const H5FD_t*, unsigned long* flags) {
  if (flags)
    *flags = H5FD_FEAT_AGGREGATE_METADATA | H5FD_FEAT_ACCUMULATE_METADATA |
             H5FD_FEAT_DATA_SIEVE | H5FD_FEAT_AGGREGATE_SMALLDATA;
  return 0;
}

haddr_t jGetEoa(const H5FD_t* f, H5FD_mem_t) { return self(f)->eoa; }
herr_t jSetEoa(H5FD_t* f, H5FD_mem_t, haddr_t addr) {
  self(f)->eoa = addr;
  return 0;
}
haddr_t jGetEof(const H5FD_t* f, H5FD_mem_t) { return self(f)->eof; }

// H5Fget_vfd_handle hands out the driver's file itself, which is how commit() finds it.
herr_t jGetHandle(H5FD_t* f, hid_t, void** handle) {
  if (!handle) return -1;
  *handle = self(f);
  return 0;
}

herr_t jRead(H5FD_t* file, H5FD_mem_t, hid_t, haddr_t addr, size_t size, void* buf) {
  JournaledFile* f = self(file);
  if (addr == HADDR_UNDEF || addr + size > f->eoa) {
    pushError(H5E_OVERFLOW, "h5journal: read past the end of the allocated space");
    return -1;
  }
  const ssize_t got = readAll(f->fd, buf, size, static_cast<off_t>(addr));
  if (got < 0) {
    pushError(H5E_READERROR, "h5journal: read failed: " + std::string(std::strerror(errno)));
    return -1;
  }
  // Bytes past the end of the file read as zeros, as in HDF5's own POSIX driver.
  std::memset(static_cast<char*>(buf) + got, 0, size - static_cast<std::size_t>(got));
  return 0;
}

herr_t jWrite(H5FD_t* file, H5FD_mem_t, hid_t, haddr_t addr, size_t size, const void* buf) {
  JournaledFile* f = self(file);
  if (addr == HADDR_UNDEF || addr + size > f->eoa) {
    pushError(H5E_OVERFLOW, "h5journal: write past the end of the allocated space");
    return -1;
  }
  if (f->failed) return 0;  // frozen at the last commit (see JournaledFile::failed)
  if (common::faultPoint("h5write")) {
    f->fail("writing '" + f->path + "' failed: " + writeErrorReason(ENOSPC) +
            " (fault injected)");
    pushError(H5E_WRITEERROR, "h5journal: " + f->failure);
    return -1;
  }
  if (!f->journalRegion(addr, size)) {
    f->fail("saving the old bytes in '" + f->journal + "' failed: " + writeErrorReason(errno));
    pushError(H5E_WRITEERROR, "h5journal: " + f->failure);
    return -1;
  }
  if (!writeAll(f->fd, buf, size, static_cast<off_t>(addr))) {
    f->fail("writing '" + f->path + "' failed: " + writeErrorReason(errno));
    pushError(H5E_WRITEERROR, "h5journal: " + f->failure);
    return -1;
  }
  f->eof = std::max<haddr_t>(f->eof, addr + size);
  return 0;
}

herr_t jFlush(H5FD_t*, hid_t, hbool_t) { return 0; }

herr_t jTruncate(H5FD_t* file, hid_t, hbool_t) {
  JournaledFile* f = self(file);
  if (f->failed || f->eoa == f->eof) return 0;
  if (f->eoa < f->eof && !f->journalRegion(f->eoa, f->eof - f->eoa)) {
    f->fail("saving the bytes that a truncation of '" + f->path + "' cuts off failed: " +
            writeErrorReason(errno));
    pushError(H5E_WRITEERROR, "h5journal: " + f->failure);
    return -1;
  }
  if (::ftruncate(f->fd, static_cast<off_t>(f->eoa)) != 0) {
    f->fail("setting the size of '" + f->path + "' failed: " + writeErrorReason(errno));
    pushError(H5E_SEEKERROR, "h5journal: " + f->failure);
    return -1;
  }
  f->eof = f->eoa;
  return 0;
}

// The writer's flock is taken at open and held until close, whatever HDF5's own file locking
// is set to (HDF5_USE_FILE_LOCKING), so these only confirm it.
herr_t jLock(H5FD_t*, hbool_t) { return 0; }
herr_t jUnlock(H5FD_t*) { return 0; }

H5FD_class_t makeClass() {
  H5FD_class_t c;
  std::memset(&c, 0, sizeof c);
  c.name = "granagg_journal";
  c.maxaddr = MAX_ADDR;
  c.fc_degree = H5F_CLOSE_WEAK;
  c.open = jOpen;
  c.close = jClose;
  c.cmp = jCmp;
  c.query = jQuery;
  c.get_eoa = jGetEoa;
  c.set_eoa = jSetEoa;
  c.get_eof = jGetEof;
  c.get_handle = jGetHandle;
  c.read = jRead;
  c.write = jWrite;
  c.flush = jFlush;
  c.truncate = jTruncate;
  c.lock = jLock;
  c.unlock = jUnlock;
  const H5FD_mem_t dichotomy[H5FD_MEM_NTYPES] = H5FD_FLMAP_DICHOTOMY;
  for (int i = 0; i < H5FD_MEM_NTYPES; ++i) c.fl_map[i] = dichotomy[i];
  return c;
}

hid_t driverId() {
  static const H5FD_class_t cls = makeClass();
  static hid_t id = H5I_INVALID_HID;
  if (id < 0 || H5Iis_valid(id) <= 0) id = H5FDregister(&cls);
  if (id < 0) h5::fail("cannot register the journaled HDF5 driver");
  return id;
}

}  // namespace

std::string journalPathFor(const std::string& path) { return path + ".journal"; }

std::int64_t fileAccess() {
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl < 0) h5::fail("cannot create a file-access property list");
  if (H5Pset_driver(fapl, driverId(), nullptr) < 0) {
    H5Pclose(fapl);
    h5::fail("cannot select the journaled HDF5 driver");
  }
  return fapl;
}

void commit(std::int64_t file) {
  const h5::Handle fapl(H5Fget_access_plist(file));
  if (!fapl || H5Pget_driver(fapl.get()) != driverId())
    throw std::invalid_argument("h5journal::commit: the file does not use the journaled driver");
  void* handle = nullptr;
  if (H5Fget_vfd_handle(file, fapl.get(), &handle) < 0 || !handle) h5::fail("h5journal::commit");
  auto* f = static_cast<JournaledFile*>(handle);
  if (!f->commitNow())
    throw std::runtime_error(
        f->failed ? "'" + f->path + "' stays at its last complete state: " + f->failure
                  : "cannot commit '" + f->path + "': emptying '" + f->journal + "' failed (" +
                        std::strerror(errno) + ")");
}

std::string writeFailure(std::int64_t file) {
  const h5::Handle fapl(H5Fget_access_plist(file));
  if (!fapl || H5Pget_driver(fapl.get()) != driverId())
    throw std::invalid_argument("h5journal::writeFailure: the file does not use the journaled "
                                "driver");
  void* handle = nullptr;
  if (H5Fget_vfd_handle(file, fapl.get(), &handle) < 0 || !handle)
    h5::fail("h5journal::writeFailure");
  return static_cast<JournaledFile*>(handle)->failure;
}

void requireWritten(std::int64_t file) {
  H5Fflush(file, H5F_SCOPE_GLOBAL);  // a failure here is recorded by the driver, read below
  h5::lastError();
  if (std::string failure = writeFailure(file); !failure.empty())
    throw std::runtime_error(std::move(failure));
}

bool pending(const std::string& path) {
  const int jfd = ::open(journalPathFor(path).c_str(), O_RDONLY | O_CLOEXEC);
  if (jfd < 0) return false;
  std::uint64_t committed = 0;
  bool torn = false;
  if (readHeader(jfd, committed)) {
    struct stat st;
    torn = !readEntries(jfd).empty() ||
           (::stat(path.c_str(), &st) == 0 && static_cast<std::uint64_t>(st.st_size) != committed);
  }
  ::close(jfd);
  return torn;
}

std::string Recovery::summary(const std::string& path) const {
  if (!repaired) return "";
  char buf[256];
  const double cut = size_before > size_after ? double(size_before - size_after) : 0.0;
  std::snprintf(buf, sizeof buf,
                "rolled back the unfinished write of '%s' that an interrupted run left "
                "(%zu blocks, %.1f kB restored; %.1f kB cut off)",
                path.c_str(), entries, bytes_restored / 1e3, cut / 1e3);
  return buf;
}

Recovery recover(const std::string& path) {
  Recovery r;
  const std::string jpath = journalPathFor(path);
  const int jfd = ::open(jpath.c_str(), O_RDONLY | O_CLOEXEC);
  if (jfd < 0) return r;  // no journal: the last writer closed the file
  struct Closer {
    int fd;
    ~Closer() {
      if (fd >= 0) ::close(fd);
    }
  } jc{jfd};
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENOENT) {
      ::unlink(jpath.c_str());
      return r;
    }
    throw std::runtime_error("cannot repair '" + path + "' from '" + jpath + "': " +
                             std::strerror(errno));
  }
  Closer fc{fd};
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0)
    throw std::runtime_error("'" + path + "' is open for writing in a running process; its " +
                             "journal '" + jpath + "' belongs to that process");
  std::uint64_t committed = 0;
  if (!readHeader(jfd, committed)) {  // empty, or torn before the first overwrite
    ::unlink(jpath.c_str());
    return r;
  }
  struct stat st;
  if (::fstat(fd, &st) != 0) throw std::runtime_error("cannot stat '" + path + "'");
  r.size_before = static_cast<std::uint64_t>(st.st_size);
  const std::vector<Entry> entries = readEntries(jfd);
  for (auto e = entries.rbegin(); e != entries.rend(); ++e) {
    if (!writeAll(fd, e->bytes.data(), e->bytes.size(), static_cast<off_t>(e->address)))
      throw std::runtime_error("cannot repair '" + path + "': writing back failed (" +
                               std::strerror(errno) + "); '" + jpath + "' is kept for a retry");
    r.bytes_restored += e->bytes.size();
  }
  r.entries = entries.size();
  if (r.size_before != committed && ::ftruncate(fd, static_cast<off_t>(committed)) != 0)
    throw std::runtime_error("cannot repair '" + path + "': truncation failed (" +
                             std::strerror(errno) + "); '" + jpath + "' is kept for a retry");
  if (::fsync(fd) != 0)
    throw std::runtime_error("cannot repair '" + path + "': fsync failed; '" + jpath +
                             "' is kept for a retry");
  r.size_after = committed;
  r.repaired = r.entries > 0 || r.size_before != committed;
  ::unlink(jpath.c_str());
  return r;
}

}  // namespace granagg::common::h5journal

#include <fcntl.h>
#include <signal.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <mutex>
#include <vector>

#include <lightvol/core/atomic_file.h>
#include <lightvol/core/path.h>

namespace lightvol {
namespace fs = std::filesystem;

// ---- Temporaries removed on SIGINT, SIGTERM, SIGHUP -------------------------------------------
// A fixed table the signal handler can walk without allocating or locking: a slot is armed
// (state 2) only once its path is complete, and the handler unlinks only the temporaries of the
// process that registered them (a forked child shares the table but not the files' fate).
namespace {
// Enough for `lightvol batch`: up to 64 jobs at once, each with a volume and a report staged.
constexpr int kSignalSlots = 256;
struct TempSlot {
  std::atomic<int> state{0};  // 0 free, 1 being filled or emptied, 2 armed
  pid_t owner = 0;
  char path[PATH_MAX] = {};
};
std::array<TempSlot, kSignalSlots> g_slots;
constexpr std::array<int, 3> kCleanupSignals = {SIGINT, SIGTERM, SIGHUP};

// While a temporary is being created and registered, or outputs renamed into place, a signal is
// deferred (on whichever thread it arrives) and acted on when that is done.
std::atomic<int> g_defer_depth{0};
std::atomic<int> g_deferred_signal{0};

// Set once a signal's cleanup begins: the process is about to die of it. Another thread may enter
// a deferring scope at that moment (it took no part in deferring the signal, or began after the
// deferred signal was acted on), to create a temporary: a file the cleanup's pass may miss, and
// that dying would leave behind before it is registered. So the cleanup, once this flag is set,
// waits for the deferring scopes to end before its last pass (sequentially consistent both ways:
// each side stores, then loads the other's), and a scope that sees the flag ends at once: on
// entering, before it creates anything; on registering, unlinking its own file first. Either way
// its thread then waits for the process to die.
std::atomic<bool> g_dying{false};

// How long the cleanup waits for the deferring scopes (a thread in one may need a lock that the
// thread the signal interrupted holds): then it goes on, and a file created meanwhile may stay.
constexpr long kScopeWaitNanoseconds = 1'000'000'000;

void unlink_armed() {
  const pid_t self = ::getpid();
  for (TempSlot& slot : g_slots)
    if (slot.state.load() == 2 && slot.owner == self) ::unlink(slot.path);
}

// Only async-signal-safe calls: clock_gettime, nanosleep, unlink.
void unlink_temporaries() {
  g_dying.store(true);
  unlink_armed();
  timespec start{}, now{};
  ::clock_gettime(CLOCK_MONOTONIC, &start);
  while (g_defer_depth.load() > 0) {
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    if ((now.tv_sec - start.tv_sec) * 1'000'000'000L + (now.tv_nsec - start.tv_nsec) >
        kScopeWaitNanoseconds)
      break;
    const timespec pause{0, 100'000};
    ::nanosleep(&pause, nullptr);
  }
  unlink_armed();
}

// A thread in a deferring scope that finds the process dying: it leaves the scope (so that the
// cleanup's wait ends) and waits to die with the process.
[[noreturn]] void leave_scope_and_wait() {
  g_defer_depth.fetch_sub(1);
  for (;;) ::pause();
}

extern "C" void unlink_temporaries_and_reraise(int sig) {
  const int saved_errno = errno;
  if (g_defer_depth.load() > 0) {
    g_deferred_signal.store(sig);
    errno = saved_errno;
    return;
  }
  unlink_temporaries();
  // SA_RESETHAND has restored the default action and SA_NODEFER leaves the signal unblocked: the
  // process now dies of it, with the status its parent expects.
  ::raise(sig);
  errno = saved_errno;
}

void install_signal_cleanup() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (int sig : kCleanupSignals) {
      struct sigaction old {};
      if (::sigaction(sig, nullptr, &old) != 0) continue;
      // Leave a program's own handler, and an ignored signal (nohup), alone.
      if ((old.sa_flags & SA_SIGINFO) != 0 || old.sa_handler != SIG_DFL) continue;
      struct sigaction act {};
      act.sa_handler = unlink_temporaries_and_reraise;
      sigemptyset(&act.sa_mask);
      act.sa_flags = SA_RESETHAND | SA_NODEFER;
      ::sigaction(sig, &act, nullptr);
    }
  });
}

// Returns the slot index, or -1 when the table is full or the path too long (the file is then
// only removed by the normal paths, not on a signal). Called in a SignalDefer scope, right after
// the file is created.
int register_temporary(const std::string& absolute_path) {
  install_signal_cleanup();
  if (absolute_path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSignalSlots; ++i) {
    int expected = 0;
    if (!g_slots[i].state.compare_exchange_strong(expected, 1)) continue;
    g_slots[i].owner = ::getpid();
    std::memcpy(g_slots[i].path, absolute_path.c_str(), absolute_path.size() + 1);
    g_slots[i].state.store(2);
    if (g_dying.load()) {  // a signal's cleanup may have passed this slot: the process dies now
      ::unlink(g_slots[i].path);
      leave_scope_and_wait();
    }
    return i;
  }
  return -1;
}

void unregister_temporary(int slot) {
  if (slot >= 0) g_slots[slot].state.store(0, std::memory_order_release);
}

// Defers the cleanup signals for the scope, on every thread (a signal may be delivered to any
// thread that does not block it): files are created and registered, or renamed into place, as a
// whole; a signal that came meanwhile is acted on at the end of the scope.
class SignalDefer {
 public:
  SignalDefer() {
    g_defer_depth.fetch_add(1);
    if (g_dying.load()) leave_scope_and_wait();  // a signal's cleanup has begun
  }
  ~SignalDefer() {
    if (g_defer_depth.fetch_sub(1) != 1) return;
    if (const int sig = g_deferred_signal.exchange(0); sig != 0) {
      unlink_temporaries();
      ::raise(sig);  // the handler reset itself on delivery: the default action now
    }
  }
  SignalDefer(const SignalDefer&) = delete;
  SignalDefer& operator=(const SignalDefer&) = delete;
};

// ---- Names ------------------------------------------------------------------------------------
// ".lv-" + 16 random characters + the target's extension: 20 bytes plus the extension, so it fits
// wherever a name with that extension fits (an extension longer than 32 bytes is dropped).
std::string random_name(const fs::path& target) {
  static constexpr char kAlphabet[] = "abcdefghijklmnopqrstuvwxyz0123456789";
  unsigned char bytes[16];
  std::size_t got = 0;
  while (got < sizeof bytes) {
    const ssize_t n = ::getrandom(bytes + got, sizeof bytes - got, 0);
    if (n > 0) {
      got += static_cast<std::size_t>(n);
    } else if (errno != EINTR) {
      // No getrandom: a per-process counter mixed with the address space and the clock still
      // gives a name nobody else predicts reliably; O_EXCL keeps it safe either way.
      static std::atomic<unsigned long> counter{0};
      unsigned long x = counter++ * 0x9E3779B97F4A7C15ul ^ reinterpret_cast<unsigned long>(&got) ^
                        static_cast<unsigned long>(::getpid()) << 32 ^
                        static_cast<unsigned long>(::clock());
      for (std::size_t i = got; i < sizeof bytes; ++i, x = x * 6364136223846793005ul + 1)
        bytes[i] = static_cast<unsigned char>(x >> 56);
      got = sizeof bytes;
    }
  }
  std::string name = ".lv-";
  for (unsigned char b : bytes) name += kAlphabet[b % 36];
  const std::string ext = target.extension().string();
  if (ext.size() <= 32) name += ext;
  return name;
}

// ---- Stale temporaries ------------------------------------------------------------------------
// A process killed by SIGKILL (or a machine that lost power) leaves its temporaries behind. The
// first write of a process into a folder removes those of this library's naming (random_name:
// ".lv-", 16 of [a-z0-9], then an extension or nothing) that are regular files with one link
// whose contents have not changed for kStaleSeconds. A live writer's temporary is younger: it is
// written from creation to rename without a pause longer than a build step takes, and a backup
// of commit_files (a hard link to a target being replaced) has two links until its rename. An
// age, not a process id, decides: a folder may be shared by machines (batch shards on NFS), where
// a process id says nothing.
constexpr std::int64_t kStaleSeconds = 3600;

bool is_temporary_name(const std::string& name) {
  if (name.size() < 20 || name.compare(0, 4, ".lv-") != 0) return false;
  for (std::size_t i = 4; i < 20; ++i)
    if (!((name[i] >= 'a' && name[i] <= 'z') || (name[i] >= '0' && name[i] <= '9'))) return false;
  return name.size() == 20 || name[20] == '.';
}

void remove_stale_temporaries(const fs::path& dir) {
  static std::mutex mutex;
  static std::vector<std::string> cleaned;  // the folders this process has cleaned
  std::error_code ec;
  const std::string key = fs::absolute(dir, ec).lexically_normal().string();
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (std::find(cleaned.begin(), cleaned.end(), key) != cleaned.end()) return;
    cleaned.push_back(key);
  }
  const std::int64_t now = static_cast<std::int64_t>(::time(nullptr));
  fs::directory_iterator it(dir, fs::directory_options::skip_permission_denied, ec);
  for (const fs::directory_iterator end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!is_temporary_name(name)) continue;
    struct stat st {};
    if (::lstat(it->path().c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink != 1) continue;
    if (now - static_cast<std::int64_t>(st.st_mtime) >= kStaleSeconds) ::unlink(it->path().c_str());
  }
}

fs::path directory_of(const fs::path& target) {
  return target.has_parent_path() ? target.parent_path() : fs::path(".");
}

// Creates a fresh file in `dir` named after `target`, exclusively; returns its path and open
// descriptor.
Result<std::pair<std::string, int>> create_temporary(const std::string& path, const fs::path& dir,
                                                     const fs::path& target) {
  for (int attempt = 0; attempt < 64; ++attempt) {
    const std::string temp = (dir / random_name(target)).string();
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0) return std::make_pair(temp, fd);
    if (errno != EEXIST)
      return Error{path + ": cannot create a file in " + dir.string() + ": " + std::strerror(errno),
                   ErrorKind::io};
  }
  return Error{
      path + ": cannot create a temporary file in " + dir.string() + ": every name tried exists",
      ErrorKind::io};
}

// Where an output goes: a file (a temporary beside it is renamed onto it; a symlink is followed
// to the file it leads to, and stays a symlink), or a stream (a descriptor the bytes are written
// through: standard output, a terminal, a pipe).
struct Destination {
  std::string target;  // a file: the path the finished temporary is renamed onto
  int fd = -1;         // a stream: an open descriptor, owned
  std::string identity;
};

Result<Destination> destination_of(const std::string& path) {
  Destination d;
  d.identity = file_identity(path);
  if (const int named = named_descriptor(path); named >= 0) {
    const int flags = ::fcntl(named, F_GETFL);
    if (flags < 0)
      return Error{path + ": descriptor " + std::to_string(named) + " is not open", ErrorKind::io};
    if ((flags & O_ACCMODE) == O_RDONLY)
      return Error{path + ": descriptor " + std::to_string(named) + " is not open for writing",
                   ErrorKind::io};
    d.fd = ::fcntl(named, F_DUPFD_CLOEXEC, 3);
    if (d.fd < 0)
      return Error{
          path + ": cannot use descriptor " + std::to_string(named) + ": " + std::strerror(errno),
          ErrorKind::io};
    return d;
  }
  Result<std::string> followed = follow_links(path);
  if (!followed) return followed.error();
  d.target = *followed;
  struct stat st {};
  if (::stat(d.target.c_str(), &st) != 0) {
    // A file to create: its folder must exist.
    std::error_code ec;
    const fs::path dir = directory_of(d.target);
    if (!fs::is_directory(dir, ec))
      return Error{path + ": directory " + dir.string() + " does not exist", ErrorKind::io};
    return d;
  }
  if (S_ISREG(st.st_mode)) return d;
  if (S_ISDIR(st.st_mode)) return Error{path + ": is a directory", ErrorKind::io};
  if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) {
    // A device or a pipe is written through: renaming a file over it would replace it.
    d.fd = ::open(d.target.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY);
    if (d.fd < 0)
      return Error{path + ": cannot open for writing: " + std::strerror(errno), ErrorKind::io};
    d.target.clear();
    return d;
  }
  return Error{
      path + ": is " + (S_ISSOCK(st.st_mode) ? "a socket" : "a block device") +
          "; outputs are written to files, character devices, pipes or standard output (-)",
      ErrorKind::io};
}

// Writes all of `bytes` to `fd` (after what the program printed: fd may be standard output).
bool write_all(int fd, const char* bytes, std::size_t size) {
  std::fflush(stdout);
  std::fflush(stderr);
  while (size > 0) {
    const ssize_t n = ::write(fd, bytes, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// Copies what the writer put in `spool` to `fd`; the spool file is gone when this returns.
Status copy_spool(const std::string& path, const std::string& spool, int fd) {
  const int in = ::open(spool.c_str(), O_RDONLY | O_CLOEXEC);
  ::unlink(spool.c_str());  // nothing left behind, whatever happens while copying
  if (in < 0)
    return Error{path + ": cannot read back the finished output: " + std::strerror(errno),
                 ErrorKind::io};
  std::vector<char> buffer(1 << 20);
  Status status;
  for (;;) {
    const ssize_t n = ::read(in, buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      status = Error{path + ": cannot read back the finished output: " + std::strerror(errno),
                     ErrorKind::io};
      break;
    }
    if (n == 0) break;
    if (!write_all(fd, buffer.data(), static_cast<std::size_t>(n))) {
      status = Error{path + ": write failed: " + std::strerror(errno), ErrorKind::io};
      break;
    }
  }
  ::close(in);
  return status;
}

}  // namespace

// ---- Transactions -----------------------------------------------------------------------------
struct OutputTransaction::Impl {
  struct Staged {
    std::string target;    // the file renamed onto (symlinks followed), or the path as given
    std::string identity;  // core/path.h file_identity, to catch one file named twice
    std::string temp;      // the finished temporary (a file) or spool (a stream); "" for bytes
    int slot = -1;
    int fd = -1;        // a stream: written through at commit
    std::string bytes;  // a stream's bytes, when there is no spool
  };
  std::vector<Staged> staged;

  void discard() {
    for (const Staged& s : staged) {
      if (!s.temp.empty()) ::unlink(s.temp.c_str());
      unregister_temporary(s.slot);
      if (s.fd >= 0) ::close(s.fd);
    }
    staged.clear();
  }
};

namespace {
thread_local OutputTransaction::Impl* t_transaction = nullptr;

// Writes a staged stream's output through its descriptor, and closes it.
Status write_through(OutputTransaction::Impl::Staged& s) {
  Status status;
  if (!s.temp.empty()) {
    status = copy_spool(s.target, s.temp, s.fd);
    unregister_temporary(s.slot);
    s.temp.clear();
  } else if (!write_all(s.fd, s.bytes.data(), s.bytes.size())) {
    status = Error{s.target + ": write failed: " + std::strerror(errno), ErrorKind::io};
  }
  ::close(s.fd);
  s.fd = -1;
  return status;
}
}  // namespace

OutputTransaction::OutputTransaction() : impl_(std::make_unique<Impl>()), previous_(t_transaction) {
  t_transaction = impl_.get();
}

OutputTransaction::~OutputTransaction() {
  impl_->discard();
  t_transaction = previous_;
}

OutputTransaction::Writer::Writer(OutputTransaction& transaction) : previous_(t_transaction) {
  t_transaction = transaction.impl_.get();
}

OutputTransaction::Writer::~Writer() { t_transaction = previous_; }

std::string OutputTransaction::staged_file(const std::string& path) const {
  const std::string identity = file_identity(path);
  for (const Impl::Staged& s : impl_->staged)
    if (s.identity == identity && s.fd < 0) return s.temp;
  return "";
}

Status OutputTransaction::commit() {
  std::vector<Impl::Staged>& staged = impl_->staged;
  if (Status s = commit_files(); !s) return s;
  // A stream may block (a full pipe): a signal now acts at once. The spools are unlinked as their
  // copies start, so nothing is left behind.
  Status status;
  for (Impl::Staged& s : staged)
    if (Status written = write_through(s); !written && status.ok()) status = written;
  staged.clear();
  return status;
}

Status OutputTransaction::commit_files() {
  SignalDefer defer;
  std::vector<Impl::Staged>& staged = impl_->staged;
  // The files first, all or nothing; the streams, which cannot be taken back, once they are in.
  std::stable_partition(staged.begin(), staged.end(),
                        [](const Impl::Staged& s) { return s.fd < 0; });
  const std::size_t files = static_cast<std::size_t>(
      std::find_if(staged.begin(), staged.end(), [](const Impl::Staged& s) { return s.fd >= 0; }) -
      staged.begin());
  // Hard links keep the files about to be replaced, so a failed rename can put them back.
  std::vector<std::string> backups(files);
  for (std::size_t i = 0; i < files; ++i) {
    struct stat st {};
    if (::lstat(staged[i].target.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
    for (int attempt = 0; attempt < 16 && backups[i].empty(); ++attempt) {
      const std::string name =
          (directory_of(staged[i].target) / random_name(staged[i].target)).string();
      if (::link(staged[i].target.c_str(), name.c_str()) == 0)
        backups[i] = name;
      else if (errno != EEXIST)
        break;  // no hard links here: that target cannot be restored
    }
  }
  auto drop_backups = [&] {
    for (const std::string& b : backups)
      if (!b.empty()) ::unlink(b.c_str());
  };
  for (std::size_t i = 0; i < files; ++i) {
    if (std::rename(staged[i].temp.c_str(), staged[i].target.c_str()) == 0) continue;
    const std::string why =
        staged[i].target +
        ": cannot move the finished file into place, no output written: " + std::strerror(errno);
    // Undo the renames done so far: each target gets its old file back, or none if it had none.
    for (std::size_t j = 0; j < i; ++j) {
      if (!backups[j].empty()) {
        if (std::rename(backups[j].c_str(), staged[j].target.c_str()) == 0) backups[j].clear();
      } else {
        ::unlink(staged[j].target.c_str());
      }
      unregister_temporary(staged[j].slot);
    }
    staged.erase(staged.begin(), staged.begin() + static_cast<std::ptrdiff_t>(i));
    impl_->discard();
    drop_backups();
    return Error{why, ErrorKind::io};
  }
  for (std::size_t i = 0; i < files; ++i) unregister_temporary(staged[i].slot);
  staged.erase(staged.begin(), staged.begin() + static_cast<std::ptrdiff_t>(files));
  drop_backups();
  return {};
}

// ---- Single files -----------------------------------------------------------------------------
namespace {

// Writes one output: `write` fills a temporary (beside a file target; in the temporary folder for
// a stream), or, with `bytes`, the bytes are the output.
Status write_output(const std::string& path,
                    const std::function<Status(const std::string& temp_path)>& write,
                    const std::string_view* bytes) {
  Result<Destination> destination = destination_of(path);
  if (!destination) return destination.error();
  Destination& d = *destination;
  struct CloseFd {
    int& fd;
    ~CloseFd() {
      if (fd >= 0) ::close(fd);
    }
  } close_fd{d.fd};
  const bool stream = d.fd >= 0;
  if (t_transaction)
    for (const OutputTransaction::Impl::Staged& s : t_transaction->staged)
      if (s.identity == d.identity)
        return Error{path + ": is also " + (s.target == path ? "another" : s.target + ", another") +
                         " output of this run; give each output its own file",
                     ErrorKind::io};

  if (stream && bytes) {
    if (t_transaction) {
      t_transaction->staged.push_back({path, d.identity, "", -1, d.fd, std::string(*bytes)});
      d.fd = -1;
      return {};
    }
    if (!write_all(d.fd, bytes->data(), bytes->size()))
      return Error{path + ": write failed: " + std::strerror(errno), ErrorKind::io};
    return {};
  }

  const fs::path target(stream ? path : d.target);
  std::error_code ec;
  const fs::path dir = stream ? fs::temp_directory_path(ec) : directory_of(target);
  if (ec) return Error{path + ": no folder for a temporary file: " + ec.message(), ErrorKind::io};
  install_signal_cleanup();
  remove_stale_temporaries(dir);
  int slot = -1;
  Result<std::pair<std::string, int>> created = Error{"", ErrorKind::io};
  {
    // A signal between creating the file and registering it would leave it behind.
    SignalDefer defer;
    created = create_temporary(path, dir, target);
    if (created) slot = register_temporary(fs::absolute(created->first, ec).string());
  }
  if (!created) return created.error();
  const auto [temp, fd] = *created;
  auto remove_temp = [&, temp = temp, fd = fd] {
    ::close(fd);
    ::unlink(temp.c_str());
    unregister_temporary(slot);
  };

  Status status;
  try {
    status =
        bytes
            ? (write_all(fd, bytes->data(), bytes->size())
                   ? Status{}
                   : Status{Error{path + ": write failed: " + std::strerror(errno), ErrorKind::io}})
            : write(temp);
  } catch (const std::bad_alloc&) {
    status = Error{path + ": out of memory while writing", ErrorKind::io};
  } catch (const std::exception& e) {
    status = Error{path + ": " + e.what(), ErrorKind::io};
  }
  if (status.ok()) {
    // The writer opened the file by name: it must still be the file created above.
    struct stat mine {
    }, now{};
    if (::fstat(fd, &mine) != 0 || ::lstat(temp.c_str(), &now) != 0 || !S_ISREG(now.st_mode))
      status = Error{path + ": the writer produced no file", ErrorKind::io};
    else if (mine.st_dev != now.st_dev || mine.st_ino != now.st_ino)
      status = Error{path + ": the temporary file " + temp + " was replaced while writing",
                     ErrorKind::io};
  }
  if (status.ok() && !stream) {
    // Replacing a file keeps its permission bits.
    struct stat old {};
    if (::stat(d.target.c_str(), &old) == 0 && S_ISREG(old.st_mode) &&
        ::fchmod(fd, old.st_mode & 07777) != 0)
      status =
          Error{path + ": cannot keep the file's mode: " + std::strerror(errno), ErrorKind::io};
  }
  if (!status.ok()) {
    remove_temp();
    return status;
  }
  ::close(fd);

  if (t_transaction) {
    t_transaction->staged.push_back({stream ? path : d.target, d.identity, temp, slot, d.fd, ""});
    d.fd = -1;
    return {};
  }
  if (stream) {
    OutputTransaction::Impl::Staged s{path, d.identity, temp, slot, d.fd, ""};
    d.fd = -1;
    return write_through(s);
  }
  SignalDefer defer;
  if (std::rename(temp.c_str(), d.target.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(temp.c_str());
    unregister_temporary(slot);
    return Error{path + ": cannot move the finished file into place: " + why, ErrorKind::io};
  }
  unregister_temporary(slot);
  return {};
}

}  // namespace

Status write_file_atomically(const std::string& path,
                             const std::function<Status(const std::string& temp_path)>& write) {
  return write_output(path, write, nullptr);
}

Status write_bytes_atomically(const std::string& path, std::string_view bytes) {
  return write_output(path, nullptr, &bytes);
}

}  // namespace lightvol

#include <fcntl.h>
#include <signal.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <vector>

#include <lightvol/core/atomic_file.h>

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

void unlink_temporaries() {
  const pid_t self = ::getpid();
  for (TempSlot& slot : g_slots)
    if (slot.state.load(std::memory_order_acquire) == 2 && slot.owner == self) ::unlink(slot.path);
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
// only removed by the normal paths, not on a signal).
int register_temporary(const std::string& absolute_path) {
  install_signal_cleanup();
  if (absolute_path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSignalSlots; ++i) {
    int expected = 0;
    if (!g_slots[i].state.compare_exchange_strong(expected, 1)) continue;
    g_slots[i].owner = ::getpid();
    std::memcpy(g_slots[i].path, absolute_path.c_str(), absolute_path.size() + 1);
    g_slots[i].state.store(2, std::memory_order_release);
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
  SignalDefer() { g_defer_depth.fetch_add(1); }
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

fs::path directory_of(const fs::path& target) {
  return target.has_parent_path() ? target.parent_path() : fs::path(".");
}

// Creates a fresh file beside `target`, exclusively; returns its path and open descriptor.
Result<std::pair<std::string, int>> create_temporary(const std::string& path,
                                                     const fs::path& target) {
  const fs::path dir = directory_of(target);
  for (int attempt = 0; attempt < 64; ++attempt) {
    const std::string temp = (dir / random_name(target)).string();
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0) return std::make_pair(temp, fd);
    if (errno != EEXIST)
      return Error{path + ": cannot create a file in " + dir.string() + ": " +
                   std::strerror(errno)};
  }
  return Error{path + ": cannot create a temporary file in " + dir.string() +
               ": every name tried exists"};
}

std::string identity_of(const fs::path& target) {
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(fs::absolute(target, ec), ec);
  return ec ? target.lexically_normal().string() : canonical.string();
}
}  // namespace

// ---- Transactions -----------------------------------------------------------------------------
struct OutputTransaction::Impl {
  struct Staged {
    std::string target;    // as given
    std::string identity;  // canonical, to catch one file named twice
    std::string temp;
    int slot = -1;
  };
  std::vector<Staged> staged;

  void discard() {
    for (const Staged& s : staged) {
      ::unlink(s.temp.c_str());
      unregister_temporary(s.slot);
    }
    staged.clear();
  }
};

namespace {
thread_local OutputTransaction::Impl* t_transaction = nullptr;
}

OutputTransaction::OutputTransaction() : impl_(std::make_unique<Impl>()), previous_(t_transaction) {
  t_transaction = impl_.get();
}

OutputTransaction::~OutputTransaction() {
  impl_->discard();
  t_transaction = previous_;
}

Status OutputTransaction::commit() {
  SignalDefer defer;
  std::vector<Impl::Staged>& staged = impl_->staged;
  // Hard links keep the files about to be replaced, so a failed rename can put them back.
  std::vector<std::string> backups(staged.size());
  for (std::size_t i = 0; i < staged.size(); ++i) {
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
  for (std::size_t i = 0; i < staged.size(); ++i) {
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
    return Error{why};
  }
  for (const Impl::Staged& s : staged) unregister_temporary(s.slot);
  staged.clear();
  drop_backups();
  return {};
}

// ---- Single files -----------------------------------------------------------------------------
Status write_file_atomically(const std::string& path,
                             const std::function<Status(const std::string& temp_path)>& write) {
  const fs::path target(path);
  std::error_code ec;
  const fs::path dir = directory_of(target);
  if (!fs::is_directory(dir, ec))
    return Error{path + ": directory " + dir.string() + " does not exist"};
  if (fs::is_directory(target, ec)) return Error{path + ": is a directory"};
  // The finished file is renamed over the target: that would replace a device or a pipe
  // (/dev/stdout) with a plain file.
  if (const fs::file_status st = fs::status(target, ec); fs::exists(st) && !fs::is_regular_file(st))
    return Error{path +
                 ": exists and is not a regular file (a device or a pipe); outputs are "
                 "written to files"};
  const std::string identity = identity_of(target);
  if (t_transaction)
    for (const OutputTransaction::Impl::Staged& s : t_transaction->staged)
      if (s.identity == identity)
        return Error{path + ": is also " + (s.target == path ? "another" : s.target + ", another") +
                     " output of this run; give each output its own file"};

  install_signal_cleanup();
  int slot = -1;
  Result<std::pair<std::string, int>> created = Error{""};
  {
    // A signal between creating the file and registering it would leave it behind.
    SignalDefer defer;
    created = create_temporary(path, target);
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
    status = write(temp);
  } catch (const std::bad_alloc&) {
    status = Error{path + ": out of memory while writing"};
  } catch (const std::exception& e) {
    status = Error{path + ": " + e.what()};
  }
  if (status.ok()) {
    // The writer opened the file by name: it must still be the file created above.
    struct stat mine {
    }, now{};
    if (::fstat(fd, &mine) != 0 || ::lstat(temp.c_str(), &now) != 0 || !S_ISREG(now.st_mode))
      status = Error{path + ": the writer produced no file"};
    else if (mine.st_dev != now.st_dev || mine.st_ino != now.st_ino)
      status = Error{path + ": the temporary file " + temp + " was replaced while writing"};
  }
  if (status.ok()) {
    // Replacing a file keeps its permission bits.
    struct stat old {};
    if (::stat(path.c_str(), &old) == 0 && S_ISREG(old.st_mode) &&
        ::fchmod(fd, old.st_mode & 07777) != 0)
      status = Error{path + ": cannot keep the file's mode: " + std::strerror(errno)};
  }
  if (!status.ok()) {
    remove_temp();
    return status;
  }
  ::close(fd);

  if (t_transaction) {
    t_transaction->staged.push_back({path, identity, temp, slot});
    return {};
  }
  SignalDefer defer;
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(temp.c_str());
    unregister_temporary(slot);
    return Error{path + ": cannot move the finished file into place: " + why};
  }
  unregister_temporary(slot);
  return {};
}

Status write_bytes_atomically(const std::string& path, std::string_view bytes) {
  return write_file_atomically(path, [&](const std::string& temp) -> Status {
    std::FILE* f = std::fopen(temp.c_str(), "wb");
    if (!f) return Error{path + ": cannot create file: " + std::strerror(errno)};
    const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    const bool closed = std::fclose(f) == 0;
    if (!ok || !closed) return Error{path + ": write failed: " + std::strerror(errno)};
    return {};
  });
}

}  // namespace lightvol

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <limits>
#include <new>
#include <string>

extern char** environ;

#include <lightvol/core/check.h>
#include <lightvol/core/detail/isolated.h>
#include <lightvol/core/limits.h>

#if defined(__SANITIZE_ADDRESS__)
#define LV_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LV_ASAN 1
#endif
#endif
#ifdef LV_ASAN
#include <sanitizer/common_interface_defs.h>
#endif

namespace lightvol {
namespace {

// Whether the child `pid` has ended (it is then a zombie until reaped), without reaping it.
bool has_ended(pid_t pid) {
  siginfo_t info{};
  while (::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) < 0)
    if (errno != EINTR) return true;  // not ours to wait for (reaped already): gone
  return info.si_pid == pid;
}

// Kills what is left of `pid`'s process group (the processes it started) and reaps `pid`: first,
// unless it has ended or is `ending` (it closed its end of the channel: it is waited for), it is
// killed, after `grace` seconds for it to end by itself (a process that dies closes its channel
// before the kernel marks it ended: a parent that saw the channel close gives it that moment, so
// that a signal it died of is not taken for ours). True when this killed it and its status says
// SIGKILL (a SIGKILL there is then ours, not another's). The group is killed while `pid` is
// unreaped, so its number cannot yet name another group.
bool end_and_reap(pid_t pid, bool ending, double grace, int* status, rusage* usage) {
  bool killed = false;
  if (ending) {
    siginfo_t info{};
    while (::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOWAIT) < 0 &&
           errno == EINTR) {
    }
  } else {
    const auto start = std::chrono::steady_clock::now();
    while (!has_ended(pid) &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < grace)
      ::usleep(1000);
    killed = !has_ended(pid);
  }
  ::kill(-pid, SIGKILL);
  if (killed) ::kill(pid, SIGKILL);  // also where it leads no group (setpgid failed)
  while (::wait4(pid, status, 0, usage) < 0 && errno == EINTR) {
  }
  return killed && WIFSIGNALED(*status) && WTERMSIG(*status) == SIGKILL;
}

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// A process's address space now (bytes), from /proc/PID/statm; 0 if unknown.
std::uint64_t process_address_space(pid_t pid) {
  const std::string path = "/proc/" + std::to_string(pid) + "/statm";
  std::FILE* f = std::fopen(path.c_str(), "r");
  if (!f) return 0;
  unsigned long long pages = 0;
  const bool ok = std::fscanf(f, "%llu", &pages) == 1;
  std::fclose(f);
  return ok ? pages * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE)) : 0;
}
std::uint64_t address_space_bytes() { return process_address_space(::getpid()); }

// RLIMIT_CPU for `seconds`: SIGXCPU, which ends the child, at the soft limit. The hard limit stays
// open, so that the parent may raise the soft one later (ChildInput::allow_more) without
// privileges; the wall-clock deadline backs it.
rlimit cpu_limit(double seconds) {
  const auto soft = static_cast<rlim_t>(std::max(1.0, std::floor(seconds)));
  return {soft, RLIM_INFINITY};
}

// In the child: no core files, `cpu` seconds of processor time, and at most `space` bytes of
// address space (not under AddressSanitizer, whose shadow memory alone exceeds any such limit).
void limit_child(double cpu, std::uint64_t space) {
  const rlimit no_core{0, 0};
  setrlimit(RLIMIT_CORE, &no_core);
  const rlimit processor = cpu_limit(cpu);
  setrlimit(RLIMIT_CPU, &processor);
#ifdef LV_ASAN
  (void)space;
  // A report in the child is the child's end, not the fuzzer's finding (libFuzzer would record
  // the parent's current input as a crash).
  __sanitizer_set_death_callback(nullptr);
#else
  if (space > 0) {
    const rlimit bytes{static_cast<rlim_t>(space), static_cast<rlim_t>(space)};
    setrlimit(RLIMIT_AS, &bytes);
  }
#endif
}

// A descriptor that becomes readable when `pid` (a child of ours, not yet reaped) ends; -1 where
// the kernel has none (before Linux 5.3), and the caller then asks has_ended().
int open_pidfd(pid_t pid) {
#ifdef SYS_pidfd_open
  return static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));  // close-on-exec by itself
#else
  (void)pid;
  return -1;
#endif
}

// Sends on a socket without SIGPIPE (a peer that is gone is an error, not a signal).
ssize_t send_some(int fd, const void* data, std::size_t bytes) {
  return ::send(fd, data, bytes, MSG_NOSIGNAL);
}

// Sends with a copy of descriptor `attach` riding on the first byte (SCM_RIGHTS).
ssize_t send_with_fd(int fd, const void* data, std::size_t bytes, int attach) {
  iovec part{const_cast<void*>(data), bytes};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
  msghdr message{};
  message.msg_iov = &part;
  message.msg_iovlen = 1;
  message.msg_control = control;
  message.msg_controllen = sizeof control;
  cmsghdr* header = CMSG_FIRSTHDR(&message);
  header->cmsg_level = SOL_SOCKET;
  header->cmsg_type = SCM_RIGHTS;
  header->cmsg_len = CMSG_LEN(sizeof(int));
  std::memcpy(CMSG_DATA(header), &attach, sizeof(int));
  return ::sendmsg(fd, &message, MSG_NOSIGNAL);
}

}  // namespace

bool ChildOutput::read_with_fd(std::uint8_t* byte, int* fd) {
  *fd = -1;
  iovec part{byte, 1};
  alignas(cmsghdr) char control[CMSG_SPACE(4 * sizeof(int))] = {};
  msghdr message{};
  message.msg_iov = &part;
  message.msg_iovlen = 1;
  message.msg_control = control;
  message.msg_controllen = sizeof control;
  ssize_t n = 0;
  do n = ::recvmsg(fd_, &message, MSG_CMSG_CLOEXEC);
  while (n < 0 && errno == EINTR);
  // Every descriptor that came is taken (the first kept, any others closed).
  for (cmsghdr* header = CMSG_FIRSTHDR(&message); header != nullptr;
       header = CMSG_NXTHDR(&message, header)) {
    if (header->cmsg_level != SOL_SOCKET || header->cmsg_type != SCM_RIGHTS) continue;
    const std::size_t count = (header->cmsg_len - CMSG_LEN(0)) / sizeof(int);
    for (std::size_t i = 0; i < count; ++i) {
      int received = -1;
      std::memcpy(&received, CMSG_DATA(header) + i * sizeof(int), sizeof(int));
      if (*fd < 0)
        *fd = received;
      else
        ::close(received);
    }
  }
  if (n == 1) return true;
  if (*fd >= 0) ::close(*fd);
  *fd = -1;
  return false;
}

void ChildOutput::write(const void* data, std::size_t bytes) {
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const ssize_t n = send_some(fd_, p, bytes);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) _exit(kChildBrokenPipe);  // the parent stopped listening
    p += n;
    bytes -= static_cast<std::size_t>(n);
  }
}

bool ChildOutput::read(void* data, std::size_t bytes) {
  char* p = static_cast<char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::read(fd_, p, bytes);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    bytes -= static_cast<std::size_t>(n);
  }
  return true;
}

bool ChildOutput::read_string(std::string* text) {
  std::uint64_t length = 0;
  if (!read_value(&length) || length > kMaxString) return false;
  text->assign(length, '\0');
  return read(text->data(), length);
}

bool ChildInput::transfer(char* data, std::size_t bytes, bool sending, int attach) {
  while (bytes > 0) {
    const double left = deadline_ - now_seconds();
    if (left <= 0) {
      timed_out_ = true;
      return false;
    }
    // The channel, and the child's end (its pidfd; without one, the kernel is asked every 50 ms).
    // Once the child has ended, only what the channel holds now is taken.
    pollfd ready[2] = {{fd_, static_cast<short>(sending ? POLLOUT : POLLIN), 0},
                       {ended_ ? -1 : pidfd_, POLLIN, 0}};
    const double wait = ended_ ? 0 : pidfd_ >= 0 ? left : std::min(left, 0.05);
    const int polled = ::poll(ready, 2, static_cast<int>(std::ceil(wait * 1000)));
    if (polled < 0 && errno == EINTR) continue;
    if (polled < 0) return false;
    if (ready[0].revents != 0) {
      const ssize_t n = attach >= 0 ? send_with_fd(fd_, data, bytes, attach)
                        : sending   ? send_some(fd_, data, bytes)
                                    : ::read(fd_, data, bytes);
      if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
      attach = -1;   // sent with the first byte
      if (n <= 0) {  // the child ended or broke off
        closed_ = true;
        return false;
      }
      data += n;
      bytes -= static_cast<std::size_t>(n);
      continue;
    }
    if (ended_) return false;  // the child is gone and the channel holds no more
    // What it wrote before it ended is in the channel already: one more look, then no waiting
    // (a process it left behind may hold the channel open).
    if (pidfd_ >= 0 ? ready[1].revents != 0 : has_ended(pid_)) ended_ = true;
  }
  return true;
}

bool ChildInput::write_with_fd(std::uint8_t byte, int fd) {
  return transfer(reinterpret_cast<char*>(&byte), 1, true, fd);
}

bool ChildInput::write(const void* data, std::size_t bytes) {
  // transfer() only reads from `data` when sending.
  return transfer(const_cast<char*>(static_cast<const char*>(data)), bytes, true);
}

bool ChildInput::write_string(const std::string& text) {
  const std::uint64_t length = std::min(text.size(), ChildOutput::kMaxString);
  return write_value(length) && write(text.data(), length);
}

void ChildOutput::write_string(const std::string& text) {
  const std::uint64_t length = std::min(text.size(), kMaxString);
  write_value(length);
  write(text.data(), length);
}

bool ChildInput::read_string(std::string* text) {
  std::uint64_t length = 0;
  if (!read_value(&length) || length > ChildOutput::kMaxString) return false;
  text->assign(length, '\0');
  return read(text->data(), length);
}

void ChildOutput::write_mesh(const Mesh& mesh) {
  write_value(static_cast<std::uint64_t>(mesh.positions.size()));
  write_value(static_cast<std::uint64_t>(mesh.indices.size()));
  write(mesh.positions.data(), mesh.positions.size() * sizeof(float));
  write(mesh.indices.data(), mesh.indices.size() * sizeof(std::uint32_t));
}

void ChildOutput::refuse(const Error& error) {
  write_value(std::uint8_t{0});
  write_string(error.message);
}

ChildInput::Verdict ChildInput::read_verdict(Error* refusal) {
  std::uint8_t flag = 0;
  if (!read_value(&flag) || flag > 1) return Verdict::broken;
  if (flag == 1) return Verdict::accepted;
  return read_string(&refusal->message) ? Verdict::refused : Verdict::broken;
}

bool ChildInput::read_mesh(Mesh* mesh, const std::string& source, Status* refused) {
  std::uint64_t floats = 0, indices = 0;
  if (!read_value(&floats) || !read_value(&indices)) return false;
  if (floats % 3 != 0 || indices % 3 != 0 ||
      floats / 3 >= std::numeric_limits<std::uint32_t>::max() ||
      indices > std::numeric_limits<std::uint64_t>::max() / 16 ||
      floats > std::numeric_limits<std::uint64_t>::max() / 16)
    return false;
  // The arrays, and the copy welding makes of them.
  if (Status s = check_memory(8 * (floats + indices), source,
                              "reading " + std::to_string(indices / 3) + " triangles");
      !s) {
    *refused = s;
    return false;
  }
  mesh->positions.resize(floats);
  mesh->indices.resize(indices);
  if (!read(mesh->positions.data(), floats * sizeof(float)) ||
      !read(mesh->indices.data(), indices * sizeof(std::uint32_t)))
    return false;
  const std::uint64_t vertices = floats / 3;
  return std::all_of(mesh->indices.begin(), mesh->indices.end(),
                     [&](std::uint32_t v) { return v < vertices; });
}

void ChildInput::allow_more(double cpu_seconds) {
  if (!(cpu_seconds > 0)) return;
  cpu_ += cpu_seconds;
  deadline_ += 4 * cpu_seconds;
  wall_added_ += 4 * cpu_seconds;
  const rlimit limit = cpu_limit(cpu_);
  ::prlimit(pid_, RLIMIT_CPU, &limit, nullptr);  // a process may set its own child's soft limits
}

bool ChildInput::read(void* data, std::size_t bytes) {
  return transfer(static_cast<char*>(data), bytes, false);
}

namespace {

// "signal N: its description".
std::string signal_text(int sig) {
  const char* name = ::strsignal(sig);
  return "signal " + std::to_string(sig) + (name ? std::string(": ") + name : "");
}

// Reaps `pid` (killed first unless it `ended` by itself), and returns the Error its end is, or
// `answer`. `cpu_base` is the processor time it had used before this request (a server's).
Status reap(const std::string& what, const IsolationLimits& limits, std::uint64_t memory, pid_t pid,
            const ChildInput& in, bool ended, double cpu_base, const Status& answer) {
  int status = 0;
  rusage usage{};
  const bool killed_by_us = end_and_reap(pid, ended, in.closed() ? 2 : 0, &status, &usage);

  const auto seconds = [](double s) {
    char text[32];
    std::snprintf(text, sizeof(text), "%g", s);
    return std::string(text);
  };
  const double used = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                      1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  const auto cpu = static_cast<double>(cpu_limit(in.cpu_seconds()).rlim_cur);
  if (WIFSIGNALED(status) &&
      (WTERMSIG(status) == SIGXCPU || (WTERMSIG(status) == SIGKILL && used >= cpu)))
    return Error{what + " used more than " +
                 seconds(std::floor(std::max(1.0, in.cpu_seconds() - cpu_base))) +
                 " s of processor time on this input and was stopped"};
  if (in.timed_out())
    return Error{what + " took longer than " +
                 seconds(limits.wall_seconds + in.wall_seconds_added()) +
                 " s on this input and was stopped"};
  if (WIFSIGNALED(status) && !killed_by_us) {
    // A signal that something outside sends (the out-of-memory killer, a user's kill), or one the
    // child's own fault raised.
    const int sig = WTERMSIG(status);
    const bool sent = sig == SIGKILL || sig == SIGTERM || sig == SIGINT || sig == SIGHUP;
    return Error{what + (sent ? " was killed (" : " crashed on this input (") + signal_text(sig) +
                 ")"};
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == kChildOutOfMemory)
    return Error{what + " ran out of memory (its limit is " + format_bytes(memory) + "; " +
                 limits.memory_advice + ")"};
  if (WIFEXITED(status) && WEXITSTATUS(status) != 0 && WEXITSTATUS(status) != kChildBrokenPipe)
    return Error{what + " failed (exit status " + std::to_string(WEXITSTATUS(status)) + ")"};
  return answer;
}

// After the child or program started: `parent` on its answer, the end of the answer, the child
// reaped, and its fate as the result.
Status supervise(const std::string& what, const IsolationLimits& limits, std::uint64_t memory,
                 pid_t pid, ChildInput& in, const std::function<Status(ChildInput&)>& parent) {
  const Status answer = parent(in);
  // The child's answer is whole: it must end (close its end) before the deadline too.
  bool ended = false;
  if (answer) {
    char extra = 0;
    while (in.read(&extra, 1)) {
      // Bytes beyond the answer are read to the end and ignored: the answer is the one parsed.
    }
    ended = !in.timed_out();
  }
  return reap(what, limits, memory, pid, in, ended, 0, answer);
}

// The processor time a process has used (its user and system time, seconds); 0 if unknown.
double process_cpu_seconds(pid_t pid) {
  const std::string path = "/proc/" + std::to_string(pid) + "/stat";
  std::FILE* f = std::fopen(path.c_str(), "r");
  if (!f) return 0;
  char line[1024];
  const std::size_t n = std::fread(line, 1, sizeof(line) - 1, f);
  std::fclose(f);
  line[n] = '\0';
  const char* p = std::strrchr(line, ')');  // after the command name, which may hold spaces
  unsigned long long utime = 0, stime = 0;
  if (!p || std::sscanf(p + 1, " %*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %llu %llu", &utime,
                        &stime) != 2)
    return 0;
  return static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// The limits of a started program for work of `cpu` more seconds and `memory` more bytes.
void limit_program(pid_t pid, double cpu_used, double cpu, std::uint64_t memory) {
  const rlimit no_core{0, 0};
  ::prlimit(pid, RLIMIT_CORE, &no_core, nullptr);
  const rlimit processor = cpu_limit(cpu_used + cpu);
  ::prlimit(pid, RLIMIT_CPU, &processor, nullptr);
#ifndef LV_ASAN
  // The soft limit only, as for the processor time: the next request sets it afresh (raising a
  // hard limit takes privileges); the program's own code never raises it.
  const std::uint64_t space = process_address_space(pid) + memory;
  const rlimit bytes{static_cast<rlim_t>(space), RLIM_INFINITY};
  ::prlimit(pid, RLIMIT_AS, &bytes, nullptr);
#else
  (void)memory;
#endif
}

// A socket pair for parent and child, both ends above the standard descriptors and the program's
// channel, close-on-exec.
bool channel_pair(int fds[2]) {
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) return false;
  for (int i = 0; i < 2; ++i) {
    if (fds[i] > kProgramChannel) continue;
    const int moved = ::fcntl(fds[i], F_DUPFD_CLOEXEC, kProgramChannel + 1);
    ::close(fds[i]);
    fds[i] = moved;
  }
  if (fds[0] >= 0 && fds[1] >= 0) {
    // Pixels and meshes cross in large answers: buffers of 4 MiB (not the default 208 KiB) cut
    // the switches between the two processes (the kernel caps them at its wmem_max/rmem_max).
    const int buffer = 4 << 20;
    for (int i = 0; i < 2; ++i) {
      ::setsockopt(fds[i], SOL_SOCKET, SO_SNDBUF, &buffer, sizeof buffer);
      ::setsockopt(fds[i], SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
    }
    return true;
  }
  for (int i = 0; i < 2; ++i)
    if (fds[i] >= 0) ::close(fds[i]);
  return false;
}

}  // namespace

Status run_isolated(const std::string& what, const IsolationLimits& limits,
                    const std::function<void(ChildOutput&)>& child,
                    const std::function<Status(ChildInput&)>& parent) {
  const std::uint64_t memory = limits.memory > 0 ? limits.memory : memory_budget();
  const std::uint64_t space = address_space_bytes() + memory;
  int fds[2];
  if (!channel_pair(fds)) return Error{what + ": cannot create a pipe: " + std::strerror(errno)};
  const double deadline = now_seconds() + limits.wall_seconds;
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int e = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    return Error{what + ": cannot start a process for it: " + std::strerror(e)};
  }
  if (pid == 0) {
    ::setpgid(0, 0);  // a group of its own (also set by the parent: whichever runs first)
    ::close(fds[0]);
    limit_child(limits.cpu_seconds, space);
    int code = 0;
    try {
      ChildOutput out(fds[1]);
      child(out);
    } catch (const std::bad_alloc&) {
      code = kChildOutOfMemory;
    } catch (...) {
      code = kChildThrew;
    }
    _exit(code);
  }
  ::setpgid(pid, 0);
  ::close(fds[1]);
  const int pidfd = open_pidfd(pid);
  ChildInput in(fds[0], pid, pidfd, limits.cpu_seconds, deadline);
  const Status result = supervise(what, limits, memory, pid, in, parent);
  ::close(fds[0]);
  if (pidfd >= 0) ::close(pidfd);
  return result;
}

namespace {

// Starts `argv[0]` with the channel as kProgramChannel; the parent's end in `*fd`.
Status spawn_program(const std::string& cannot, const std::vector<std::string>& argv, pid_t* pid,
                     int* fd) {
  LV_CHECK(!argv.empty());
  int fds[2];
  if (!channel_pair(fds)) return Error{cannot + std::strerror(errno) + ")"};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], kProgramChannel);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, STDERR_FILENO, STDOUT_FILENO);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setpgroup(&attributes, 0);  // a process group of its own, to be ended whole
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETPGROUP);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const int spawned =
      ::posix_spawn(pid, argv[0].c_str(), &actions, &attributes, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  ::close(fds[1]);
  if (spawned != 0) {
    ::close(fds[0]);
    return Error{cannot + std::strerror(spawned) + ")"};
  }
  *fd = fds[0];
  return {};
}

// Waits for the program's kProgramReady; else kills and reaps it and says why it is not ready.
Status await_ready(const std::string& cannot, pid_t pid, ChildInput& in) {
  std::uint8_t ready = 0;
  if (in.read_value(&ready) && ready == kProgramReady) return {};
  int status = 0;
  rusage usage{};
  const bool killed = end_and_reap(pid, false, in.closed() ? 2 : 0, &status, &usage);
  if (in.timed_out()) return Error{cannot + "it did not get ready in time)"};
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
    return Error{cannot + "it could not be executed)"};
  if (WIFSIGNALED(status) && !killed)
    return Error{cannot + "it ended with " + signal_text(WTERMSIG(status)) +
                 " before it was ready)"};
  return Error{cannot + "it ended before it was ready)"};
}

}  // namespace

Result<std::unique_ptr<IsolatedServer>> IsolatedServer::start(const std::string& what,
                                                              const std::vector<std::string>& argv,
                                                              double wall_seconds) {
  const std::string cannot = what + " could not be started (" + argv.at(0) + ": ";
  pid_t pid = -1;
  int fd = -1;
  if (Status s = spawn_program(cannot, argv, &pid, &fd); !s) return s.error();
  const int pidfd = open_pidfd(pid);
  ChildInput in(fd, pid, pidfd, 0, now_seconds() + wall_seconds);
  if (Status s = await_ready(cannot, pid, in); !s) {
    ::close(fd);
    if (pidfd >= 0) ::close(pidfd);
    return s.error();
  }
  return std::unique_ptr<IsolatedServer>(new IsolatedServer(pid, fd, pidfd));
}

IsolatedServer::~IsolatedServer() {
  if (fd_ >= 0) ::close(fd_);
  if (pid_ > 0) {
    // It ends when it reads the end of its channel; wait a moment for that, then end it and what
    // it left behind.
    for (int i = 0; i < 100 && !has_ended(pid_); ++i) ::usleep(1000);
    int status = 0;
    rusage usage{};
    end_and_reap(pid_, false, 0, &status, &usage);
  }
  if (pidfd_ >= 0) ::close(pidfd_);
}

Status IsolatedServer::request(const std::string& what, const IsolationLimits& limits,
                               const std::function<Status(ChildInput&)>& parent) {
  LV_CHECK(alive());
  const std::uint64_t memory = limits.memory > 0 ? limits.memory : memory_budget();
  const double used = process_cpu_seconds(pid_);
  limit_program(pid_, used, limits.cpu_seconds, memory);
  ChildInput in(fd_, pid_, pidfd_, used + limits.cpu_seconds, now_seconds() + limits.wall_seconds);
  const Status answer = parent(in);
  std::uint8_t ready = 0;
  if (answer && in.read_value(&ready) && ready == kProgramReady) return answer;
  // Its answer broke off, or it did not come back: it ends here, and its end is the error.
  const Status result = reap(what, limits, memory, pid_, in, false, used, answer);
  pid_ = -1;
  return result;
}

}  // namespace lightvol

// A lightvol-image that misbehaves on request: it serves images as the real one does, except that
// a read of a path containing "crash" ends it with SIGSEGV, "killed" with SIGKILL (as the
// out-of-memory killer would), "exit" with exit status 3, and one containing "hang" never answers.
// With $LIGHTVOL_FAKE_GRANDCHILD set to a path, it first forks a grandchild that sleeps holding the
// channel, and writes the grandchild's pid to that file before it is ready. For the tests of how a
// failing decoder is reported (image_helper_test.cpp).
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/isolated.h>
#include <lightvol/depth/detail/image_codec.h>

namespace {

// Peeks at the first `size` bytes of the channel (leaving them for the real server): false at the
// end of the channel (also part way through) or on an error. A peek on a stream socket returns what
// has arrived so far, even with MSG_WAITALL, and the request may come in more than one write: the
// first peek blocks until the request starts, then the peek repeats (a millisecond apart) until all
// of it is there.
bool peek(char* out, std::size_t size) {
  for (;;) {
    const ssize_t got = ::recv(lightvol::kProgramChannel, out, size, MSG_PEEK);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    if (static_cast<std::size_t>(got) == size) return true;
    pollfd channel{lightvol::kProgramChannel, POLLIN, 0};
    if (::poll(&channel, 1, 0) > 0 && (channel.revents & POLLHUP) != 0) return false;  // no more
    const timespec millisecond{0, 1000000};
    ::nanosleep(&millisecond, nullptr);
  }
}

// The path of the next request, peeked at (left in the channel for the real server).
std::string peek_path() {
  char head[1 + 8];
  if (!peek(head, sizeof head)) return {};
  std::uint64_t length = 0;
  std::memcpy(&length, head + 1, sizeof length);
  if (length > 4096) return {};
  std::string all(sizeof head + length, '\0');
  if (!peek(all.data(), all.size())) return {};
  return all.substr(sizeof head);
}

// A process that sleeps holding the channel (inherited), its pid written to `pid_file`.
void leave_a_grandchild(const char* pid_file) {
  const pid_t grandchild = ::fork();
  if (grandchild == 0) {
    const int null = ::open("/dev/null", O_RDWR);
    ::dup2(null, 1);  // not the test's output, which ctest waits on
    ::dup2(null, 2);
    ::alarm(300);  // a backstop where it is not killed (the defect the tests look for)
    for (;;) ::pause();
  }
  std::FILE* f = std::fopen(pid_file, "w");
  if (f) {
    std::fprintf(f, "%d\n", static_cast<int>(grandchild));
    std::fclose(f);
  }
}

}  // namespace

int main() {
  if (const char* pid_file = std::getenv("LIGHTVOL_FAKE_GRANDCHILD")) leave_a_grandchild(pid_file);
  lightvol::ChildOutput channel(lightvol::kProgramChannel);
  channel.write_value(lightvol::kProgramReady);
  for (;;) {
    const std::string path = peek_path();
    if (path.find("crash") != std::string::npos) {
      std::signal(SIGSEGV, SIG_DFL);  // a plain crash, also under AddressSanitizer's handler
      std::raise(SIGSEGV);
    }
    if (path.find("killed") != std::string::npos) std::raise(SIGKILL);
    if (path.find("exit") != std::string::npos) std::_Exit(3);
    if (path.find("hang") != std::string::npos) ::pause();
    if (!lightvol::detail::serve_image_request(channel, 0)) return 0;
    channel.write_value(lightvol::kProgramReady);
  }
}

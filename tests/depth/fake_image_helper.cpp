// A lightvol-image that misbehaves on request: it serves images as the real one does, except that
// a read of a path containing "crash" ends it with SIGSEGV and one containing "hang" never
// answers. For the tests of how a failing decoder is reported (image_helper_test.cpp).
#include <sys/socket.h>
#include <unistd.h>

#include <csignal>
#include <cstdint>
#include <cstring>
#include <string>

#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/isolated.h>
#include <lightvol/depth/detail/image_codec.h>

namespace {

// The path of the next request, peeked at (left in the channel for the real server).
std::string peek_path() {
  char head[1 + 8];
  if (::recv(lightvol::kProgramChannel, head, sizeof head, MSG_PEEK | MSG_WAITALL) !=
      static_cast<ssize_t>(sizeof head))
    return {};
  std::uint64_t length = 0;
  std::memcpy(&length, head + 1, sizeof length);
  if (length > 4096) return {};
  std::string all(sizeof head + length, '\0');
  if (::recv(lightvol::kProgramChannel, all.data(), all.size(), MSG_PEEK | MSG_WAITALL) !=
      static_cast<ssize_t>(all.size()))
    return {};
  return all.substr(sizeof head);
}

}  // namespace

int main() {
  lightvol::ChildOutput channel(lightvol::kProgramChannel);
  channel.write_value(lightvol::kProgramReady);
  for (;;) {
    const std::string path = peek_path();
    if (path.find("crash") != std::string::npos) {
      std::signal(SIGSEGV, SIG_DFL);  // a plain crash, also under AddressSanitizer's handler
      std::raise(SIGSEGV);
    }
    if (path.find("hang") != std::string::npos) ::pause();
    if (!lightvol::detail::serve_image_request(channel, 0)) return 0;
    channel.write_value(lightvol::kProgramReady);
  }
}

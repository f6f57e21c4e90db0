// read_bench IMAGE [N]: reads IMAGE N times (default 3) with read_depth_image and prints, per read,
// the wall-clock seconds and the processor seconds (user, system) of this process and of its
// lightvol-image server (from /proc), to see where reading a large image spends its time.
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <lightvol/depth/depth_image.h>

namespace {

double seconds(const timeval& t) {
  return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
}

// User and system seconds of this process's children (the running lightvol-image server).
void children_cpu(double* user, double* system) {
  *user = *system = 0;
  std::ifstream list("/proc/self/task/" + std::to_string(::getpid()) + "/children");
  int pid = 0;
  while (list >> pid) {
    std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
    std::string line;
    std::getline(stat, line);
    std::istringstream fields(line.substr(line.rfind(')') + 2));
    std::string field;
    for (int i = 3; i <= 13; ++i) fields >> field;
    double u = 0, s = 0;
    fields >> u >> s;
    const double tick = static_cast<double>(::sysconf(_SC_CLK_TCK));
    *user += u / tick;
    *system += s / tick;
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: read_bench IMAGE [N]\n");
    return 2;
  }
  const int n = argc > 2 ? std::atoi(argv[2]) : 3;
  std::printf("wall_s self_user self_sys helper_user helper_sys\n");
  for (int i = 0; i < n; ++i) {
    rusage before{}, after{};
    double hu0 = 0, hs0 = 0, hu1 = 0, hs1 = 0;
    children_cpu(&hu0, &hs0);
    ::getrusage(RUSAGE_SELF, &before);
    const auto start = std::chrono::steady_clock::now();
    {
      const lightvol::Result<lightvol::DepthImage> image = lightvol::read_depth_image(argv[1]);
      if (!image) {
        std::fprintf(stderr, "read_bench: %s\n", image.error().message.c_str());
        return 1;
      }
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ::getrusage(RUSAGE_SELF, &after);
    children_cpu(&hu1, &hs1);
    if (i == 0) hu0 = hs0 = 0;  // the server started during the first read
    std::printf("%.3f %.3f %.3f %.3f %.3f\n", wall,
                seconds(after.ru_utime) - seconds(before.ru_utime),
                seconds(after.ru_stime) - seconds(before.ru_stime), hu1 - hu0, hs1 - hs0);
  }
  return 0;
}

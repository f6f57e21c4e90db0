// make_depth W H OUT: writes the synthetic benchmark shadow map (synthetic_scene.h) to OUT.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "synthetic_scene.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: make_depth WIDTH HEIGHT OUT.exr\n");
    return 2;
  }
  const int w = std::atoi(argv[1]), h = std::atoi(argv[2]);
  if (w < 2 || h < 2) {
    std::fprintf(stderr, "make_depth: sizes must be >= 2\n");
    return 2;
  }
  const lightvol::Status s =
      lightvol::write_depth_image(argv[3], lightvol::bench::synthetic_scene(w, h));
  if (!s) {
    std::fprintf(stderr, "make_depth: %s\n", s.error().message.c_str());
    return 2;
  }
  return 0;
}

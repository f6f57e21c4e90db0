// make_omni_depth W OUT: writes the synthetic omni room (omni_scene.h) as six faces, OUT
// containing {face} (px nx py ny pz nz), or as one W × 6W strip otherwise; prints the light JSON.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "support/omni_scene.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr,
                 "usage: make_omni_depth W OUT (OUT with {face} for six files, else a strip)\n");
    return 2;
  }
  const int w = std::atoi(argv[1]);
  if (w < 2) {
    std::fprintf(stderr, "make_omni_depth: W must be >= 2\n");
    return 2;
  }
  const std::string out = argv[2];
  const lightvol::CubeFaces cube = lightvol::test::omni_scene(w);
  if (out.find("{face}") == std::string::npos) {
    if (lightvol::Status s = lightvol::write_depth_image(out, lightvol::stack_cube_faces(cube));
        !s) {
      std::fprintf(stderr, "make_omni_depth: %s\n", s.error().message.c_str());
      return 2;
    }
  } else {
    for (int f = 0; f < lightvol::kOmniFaces; ++f) {
      const lightvol::Status s =
          lightvol::write_depth_image(lightvol::expand_face_pattern(out, f), cube.faces[f]);
      if (!s) {
        std::fprintf(stderr, "make_omni_depth: %s\n", s.error().message.c_str());
        return 2;
      }
    }
  }
  std::printf("%s\n", lightvol::test::omni_scene_light_json().c_str());
  return 0;
}

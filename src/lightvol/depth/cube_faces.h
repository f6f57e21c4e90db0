// Omni-light depth input (docs/design.md §2): six square faces in the order +X −X +Y −Y +Z −Z.
//
// Three forms on disk: six files in that order; one path containing `{face}`, expanded to
// px nx py ny pz nz; or one vertical strip W × 6W with the faces stacked top to bottom in that
// order (face i occupies stored rows [i·W, (i+1)·W)). Each face is an ordinary depth image of the
// face's 90° view (first stored row = the top of that view unless the light's flip_y).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <lightvol/core/result.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/light/light.h>

namespace lightvol {

struct CubeFaces {
  std::array<DepthImage, kOmniFaces> faces;     // +X −X +Y −Y +Z −Z, all W×W
  std::array<std::string, kOmniFaces> sources;  // what names each face in errors (file, or strip)

  int size() const { return faces[0].width; }
};

// "+X (px)", "-Y (ny)", ...: how errors name a face.
std::string omni_face_name(int face);

// `pattern` with every "{face}" replaced by the face's tag (px nx py ny pz nz).
std::string expand_face_pattern(const std::string& pattern, int face);

// The files `paths` (a light's depth inputs, as read_shadow_maps takes them) name: a path with
// {face} as its six faces (px nx py ny pz nz), every other path as given, in order. What a caller
// that must know every file a build reads (an output may not replace one; a job's content hash
// covers them) lists.
std::vector<std::string> depth_input_files(const std::vector<std::string>& paths);

// Every face square, at least 2×2, and all the same size; the Error names the source and the face.
Status validate_cube_faces(const CubeFaces& cube);

// Splits a W × 6W strip into its six faces. `source` names the strip in errors (wrong shape) and,
// with the face, in each face's source.
Result<CubeFaces> split_cube_strip(const DepthImage& strip, const std::string& source);

// The inverse: the six (equal, square) faces stacked top to bottom into one W × 6W strip.
DepthImage stack_cube_faces(const CubeFaces& cube);

// Reads an omni light's depth input: six paths, one path containing {face}, or one strip path.
// Errors name the file and the face: a missing or unreadable face, a face that is not square, a
// face whose size differs from +X's, a strip that is not W × 6W, or a wrong number of paths.
Result<CubeFaces> read_cube_faces(const std::vector<std::string>& paths,
                                  const DepthReadOptions& options = {});

}  // namespace lightvol

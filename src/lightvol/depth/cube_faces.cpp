#include <lightvol/core/check.h>
#include <lightvol/depth/cube_faces.h>

namespace lightvol {
namespace {

constexpr std::string_view kFacePlaceholder = "{face}";

std::string size_text(const DepthImage& image) {
  return std::to_string(image.width) + "x" + std::to_string(image.height);
}

// "path: why" → "path: face +Y (py): why", so that a read error names the face after the file.
std::string with_face(const std::string& message, const std::string& path, int face) {
  const std::string prefix = path + ": ";
  if (message.compare(0, prefix.size(), prefix) == 0)
    return prefix + "face " + omni_face_name(face) + ": " + message.substr(prefix.size());
  return path + ": face " + omni_face_name(face) + ": " + message;
}

// Face f square, at least 2×2, its values complete, and the size of face 0.
Status check_face(const CubeFaces& cube, int f) {
  const DepthImage& image = cube.faces[f];
  const std::string where = cube.sources[f] + ": face " + omni_face_name(f) + ": ";
  if (image.width != image.height)
    return Error{where + "is " + size_text(image) + "; omni faces must be square"};
  if (image.width < 2)
    return Error{where + "is " + size_text(image) + "; faces need at least 2x2 texels"};
  if (image.values.size() != static_cast<std::size_t>(image.width) * image.height)
    return Error{where + "holds " + std::to_string(image.values.size()) + " values for " +
                 size_text(image) + " texels"};
  if (f > 0 && image.width != cube.faces[0].width)
    return Error{where + "is " + size_text(image) + ", but face " + omni_face_name(0) + " (" +
                 cube.sources[0] + ") is " + size_text(cube.faces[0]) +
                 "; all six faces must be the same size"};
  return {};
}

}  // namespace

std::string omni_face_name(int face) {
  static constexpr const char* names[kOmniFaces] = {"+X", "-X", "+Y", "-Y", "+Z", "-Z"};
  LV_CHECK(face >= 0 && face < kOmniFaces);
  return std::string(names[face]) + " (" + std::string(omni_face_tag(face)) + ")";
}

std::string expand_face_pattern(const std::string& pattern, int face) {
  std::string out = pattern;
  const std::string tag(omni_face_tag(face));
  for (std::size_t at = out.find(kFacePlaceholder); at != std::string::npos;
       at = out.find(kFacePlaceholder, at + tag.size()))
    out.replace(at, kFacePlaceholder.size(), tag);
  return out;
}

Status validate_cube_faces(const CubeFaces& cube) {
  for (int f = 0; f < kOmniFaces; ++f)
    if (Status s = check_face(cube, f); !s) return s;
  return {};
}

Result<CubeFaces> split_cube_strip(const DepthImage& strip, const std::string& source) {
  if (strip.width < 2 || strip.height != kOmniFaces * strip.width)
    return Error{source + ": is " + size_text(strip) +
                 "; a single omni depth image must be a vertical strip W x 6W holding the faces "
                 "+X -X +Y -Y +Z -Z from top to bottom (or give six images, or a {face} path)"};
  CubeFaces cube;
  const std::size_t face_texels = static_cast<std::size_t>(strip.width) * strip.width;
  for (int f = 0; f < kOmniFaces; ++f) {
    DepthImage& face = cube.faces[f];
    face.width = face.height = strip.width;
    const auto begin = strip.values.begin() + static_cast<std::ptrdiff_t>(f * face_texels);
    face.values.assign(begin, begin + static_cast<std::ptrdiff_t>(face_texels));
    cube.sources[f] = source + " (strip rows " + std::to_string(f * strip.width) + ".." +
                      std::to_string((f + 1) * strip.width - 1) + ")";
  }
  return cube;
}

DepthImage stack_cube_faces(const CubeFaces& cube) {
  LV_CHECK(validate_cube_faces(cube).ok());
  DepthImage strip;
  strip.width = cube.size();
  strip.height = kOmniFaces * strip.width;
  strip.values.reserve(static_cast<std::size_t>(strip.width) * strip.height);
  for (const DepthImage& face : cube.faces)
    strip.values.insert(strip.values.end(), face.values.begin(), face.values.end());
  return strip;
}

std::vector<std::string> depth_input_files(const std::vector<std::string>& paths) {
  std::vector<std::string> files;
  for (const std::string& p : paths) {
    if (p.find(kFacePlaceholder) == std::string::npos) {
      files.push_back(p);
      continue;
    }
    for (int face = 0; face < kOmniFaces; ++face) files.push_back(expand_face_pattern(p, face));
  }
  return files;
}

Result<CubeFaces> read_cube_faces(const std::vector<std::string>& paths,
                                  const DepthReadOptions& options) {
  std::array<std::string, kOmniFaces> face_paths;
  for (const std::string& p : paths)
    if (p.find(kFacePlaceholder) != std::string::npos && paths.size() != 1)
      return Error{p +
                   ": a path with {face} stands for all six faces and must be the only depth "
                   "path, got " +
                   std::to_string(paths.size()) + " paths"};
  if (paths.size() == 1 && paths[0].find(kFacePlaceholder) == std::string::npos) {
    Result<DepthImage> strip = read_depth_image(paths[0], options);
    if (!strip) return strip.error();
    return split_cube_strip(*strip, paths[0]);
  }
  const std::vector<std::string> files = depth_input_files(paths);  // {face}: six
  if (files.size() == kOmniFaces) {
    for (int f = 0; f < kOmniFaces; ++f) face_paths[f] = files[f];
  } else {
    return Error{
        "an omni light takes six depth images (+X -X +Y -Y +Z -Z), one path containing "
        "{face}, or one W x 6W strip; got " +
        std::to_string(paths.size()) + " paths"};
  }

  CubeFaces cube;
  DepthReadOptions face_options = options;
  face_options.images = kOmniFaces;  // the budget counts all six faces from the first header
  for (int f = 0; f < kOmniFaces; ++f) {
    Result<DepthImage> image = read_depth_image(face_paths[f], face_options);
    if (!image) return Error{with_face(image.error().message, face_paths[f], f)};
    cube.faces[f] = std::move(*image);
    cube.sources[f] = face_paths[f];
    // Check as we go: a mismatch is reported before the remaining faces are read.
    if (Status s = check_face(cube, f); !s) return s.error();
  }
  if (Status s = validate_cube_faces(cube); !s) return s.error();
  return cube;
}

}  // namespace lightvol

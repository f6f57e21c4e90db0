#include <lightvol/render/detail/density_glsl.h>
#include <lightvol/render/gl_density.h>

namespace lightvol {

using namespace gl;

const char* const kGlslDensity = detail::kDensityGlsl;

void set_density_uniforms(const Program& program, const Density& density) {
  const NoiseDensity& n = density.noise;
  glUniform1i(program.uniform("density_type"), density.varying() ? 1 : 0);
  glUniform1ui(program.uniform("density_seed"), n.seed);
  glUniform1f(program.uniform("density_frequency"), static_cast<float>(n.frequency));
  glUniform1i(program.uniform("density_octaves"), n.octaves);
  glUniform1f(program.uniform("density_lacunarity"), static_cast<float>(n.lacunarity));
  glUniform1f(program.uniform("density_gain"), static_cast<float>(n.gain));
  glUniform1f(program.uniform("density_offset"), static_cast<float>(n.offset));
  glUniform1f(program.uniform("density_scale"), static_cast<float>(n.scale));
}

}  // namespace lightvol

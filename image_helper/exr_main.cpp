// lightvol-exr: reads plain EXR depth maps for the lightvol library (depth/detail/exr_codec.h),
// answering read requests one after another on file descriptor 3, as lightvol-image does, until it
// closes. It links OpenEXR's C core (and libdeflate) and not OpenImageIO or OpenVDB: it starts in
// a fraction of lightvol-image's time. Every file that is not plain it declines, and the library
// reads it through lightvol-image. Not meant to be run by hand.
#include <lightvol/core/detail/program_main.h>
#include <lightvol/depth/detail/exr_codec.h>

int main(int argc, char** argv) {
  return lightvol::detail::run_reader_program(
      argc, argv, "lightvol-exr: the lightvol library's reader of plain EXR depth maps",
      [](lightvol::ChildOutput& channel) {
        return lightvol::detail::serve_exr_request(channel, 0);
      });
}

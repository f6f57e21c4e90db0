// lightvol-image: decodes and encodes images, and reads OpenVDB density grids, for the lightvol
// library, answering requests one after another on file descriptor 3 (core/detail/isolated.h
// IsolatedServer; the requests are core/detail/image_helper.h's, the answers
// depth/detail/image_codec.h's and airlight/detail/vdb_codec.h's) until it closes. The only program
// of lightvol that links OpenImageIO and OpenVDB; not meant to be run by hand.
#include <lightvol/airlight/detail/vdb_codec.h>
#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/program_main.h>
#include <lightvol/depth/detail/image_codec.h>

int main(int argc, char** argv) {
  return lightvol::detail::run_reader_program(
      argc, argv, "lightvol-image: the lightvol library's image decoder",
      [](lightvol::ChildOutput& channel) {
        using lightvol::detail::ImageRequest;
        ImageRequest request{};
        return channel.read_value(&request) &&
               (request == ImageRequest::vdb
                    ? lightvol::detail::serve_vdb_request(channel)
                    : lightvol::detail::serve_image_request(channel, 0, request));
      });
}

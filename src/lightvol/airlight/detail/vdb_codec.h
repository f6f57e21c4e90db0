// lightvol-image's side of reading OpenVDB density grids (vdb_file.h read_vdb_grid): the only file
// of lightvol that includes OpenVDB's headers. Linked into lightvol-image (and tests), never into
// the lightvol library.
#pragma once

#include <lightvol/core/detail/isolated.h>

namespace lightvol::detail {

// Answers one ImageRequest::vdb (its first byte already read) on `channel`: the conversation of
// vdb_file.h. False when the request broke off.
bool serve_vdb_request(ChildOutput& channel);

}  // namespace lightvol::detail

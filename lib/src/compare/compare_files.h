// Comparing two image files: channels selected by name across all subimages, read with OIIO,
// for ssgi's metrics (compare_files, in ssgi/compare.h) and for idiff's comparison.
#pragma once

#include <string>
#include <vector>

#include "compare/idiff.h"
#include "io/layout.h"
#include "ssgi/compare.h"

namespace ssgi {

// Resolves `--channels` items against two files' channels. An item is NAME or A_NAME=B_NAME;
// a name is a channel, or a layer whose R, G, B channels are compared. Channels are grouped
// into layers by their prefix before the last '.'. With no items: every layer that has R, G, B
// in both files (the root layer too). Multi-part channels without a layer of their own are
// named `<part>.<channel>`. Throws Error(kUsage) on a malformed item and Error(kInput) naming
// the file that lacks a channel, or when no RGB layer is common.
std::vector<LayerChannels> select_layers(const std::string& a_path, const FileChannels& a,
                                         const std::string& b_path, const FileChannels& b,
                                         const std::vector<std::string>& items);

// Compares `a_path` with `b_path` as idiff does and writes the difference image when asked
// (atomically). Throws Error(kIO) naming a file that cannot be read or written, Error(kInput)
// for deep data or a channel --channels names that is missing, Error(kUsage) for channels
// together with all_subimages.
IdiffFileResult idiff_files(const std::string& a_path, const std::string& b_path,
                            const IdiffOptions& options);

}  // namespace ssgi

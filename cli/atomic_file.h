// The files the programs write besides frames (statistics, tables, plots): under a hidden
// temporary name in the same directory, renamed into place when whole, so that a failure or a
// signal never leaves a partial file under the name asked for.
#pragma once

#include <functional>
#include <string>

namespace ssgi_cli {

// Makes the missing directories of `path`, lets `write` write the temporary file it is given
// (false on failure, with *why saying what went wrong if it knows), and renames that into
// place. The temporary file is registered for the signal handler and removed on failure.
// Throws Error(kIO) naming `path`: "cannot write the <what>[: why]".
void write_atomically(const std::string& path, const std::string& what,
                      const std::function<bool(const std::string& tmp, std::string* why)>& write);

// `text` as the whole file, atomically.
void write_text_atomically(const std::string& path, const std::string& text,
                           const std::string& what);

}  // namespace ssgi_cli

#include "atomic_file.h"

#include <filesystem>
#include <fstream>

#include "io/temporary_files.h"
#include "ssgi/error.h"

namespace ssgi_cli {

namespace fs = std::filesystem;

void write_atomically(const std::string& path, const std::string& what,
                      const std::function<bool(const std::string& tmp, std::string* why)>& write) {
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  const std::string tmp =
      (target.parent_path() / ("." + target.filename().string() + ".tmp")).string();
  const ssgi::TemporaryFile registered(tmp);  // removed by a signal handler
  std::string why;
  if (write(tmp, &why)) {
    fs::rename(tmp, path, ec);
    if (!ec) return;
    why = ec.message();
  }
  fs::remove(tmp, ec);
  ssgi::throw_io(path, "cannot write the " + what + (why.empty() ? "" : ": " + why));
}

void write_text_atomically(const std::string& path, const std::string& text,
                           const std::string& what) {
  write_atomically(path, what, [&text](const std::string& tmp, std::string*) {
    std::ofstream file(tmp, std::ios::binary);
    file << text;
    file.flush();
    return file.good();
  });
}

}  // namespace ssgi_cli

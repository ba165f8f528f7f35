// The shared helpers of the command line's end-to-end tests (cli_support.h).
#include "cli_support.h"

#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cmath>
#include <iterator>

extern char** environ;

namespace cli_test {

CliResult run_ssgi(const std::vector<std::string>& args) {
  std::vector<std::string> argv_storage = {SSGI_BINARY};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_storage) argv.push_back(a.data());
  argv.push_back(nullptr);

  int out_pipe[2], err_pipe[2];
  if (::pipe(out_pipe) != 0 || ::pipe(err_pipe) != 0) return {};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], STDERR_FILENO);
  for (int fd : {out_pipe[0], out_pipe[1], err_pipe[0], err_pipe[1]})
    posix_spawn_file_actions_addclose(&actions, fd);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);

  CliResult result;
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&result.out, &result.err};
  int open_fds = 2;
  while (spawned == 0 && open_fds > 0) {
    if (::poll(fds, 2, -1) < 0) break;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      char buf[4096];
      const ssize_t got = ::read(fds[i].fd, buf, sizeof buf);
      if (got > 0) {
        sinks[i]->append(buf, static_cast<std::size_t>(got));
      } else {
        ::close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  for (const pollfd& p : fds)
    if (p.fd >= 0) ::close(p.fd);
  int status = 0;
  if (spawned == 0 && ::waitpid(pid, &status, 0) == pid && WIFEXITED(status))
    result.exit_code = WEXITSTATUS(status);
  return result;
}

ExrImage read_exr(const std::string& path) {
  ExrImage image;
  auto in = OIIO::ImageInput::open(path);
  EXPECT_TRUE(in) << path << ": " << OIIO::geterror();
  if (!in) return image;
  image.spec = in->spec();
  const int n = image.spec.nchannels;
  const std::size_t pixels = static_cast<std::size_t>(image.spec.width) * image.spec.height;
  std::vector<float> interleaved(pixels * n);
  EXPECT_TRUE(in->read_image(0, 0, 0, n, OIIO::TypeDesc::FLOAT, interleaved.data()))
      << path << ": " << in->geterror();
  for (int c = 0; c < n; ++c) {
    std::vector<float>& plane = image.planes[image.spec.channelnames[c]];
    plane.resize(pixels);
    for (std::size_t p = 0; p < pixels; ++p) plane[p] = interleaved[p * n + c];
  }
  return image;
}

void write_exr(const std::string& path, const ExrImage& image) {
  OIIO::ImageSpec spec = image.spec;
  spec.set_format(OIIO::TypeDesc::FLOAT);
  spec.channelformats.clear();
  spec.alpha_channel = -1;
  spec.z_channel = -1;
  spec.nchannels = static_cast<int>(spec.channelnames.size());
  const std::size_t pixels = static_cast<std::size_t>(spec.width) * spec.height;
  std::vector<float> interleaved(pixels * spec.nchannels);
  for (int c = 0; c < spec.nchannels; ++c) {
    const std::vector<float>& plane = image.planes.at(spec.channelnames[c]);
    for (std::size_t p = 0; p < pixels; ++p) interleaved[p * spec.nchannels + c] = plane[p];
  }
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out && out->open(path, spec) &&
              out->write_image(OIIO::TypeDesc::FLOAT, interleaved.data()) && out->close())
      << path;
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

double IndirectRelRmse(const ExrImage& a, const ExrImage& b, const std::string& depth_channel) {
  const std::vector<float>& depth = b.planes.at(depth_channel);
  double squared = 0, sum = 0;
  std::size_t n = 0;
  for (const char* c : {"indirect.R", "indirect.G", "indirect.B"}) {
    const std::vector<float>& pa = a.planes.at(c);
    const std::vector<float>& pb = b.planes.at(c);
    for (std::size_t i = 0; i < depth.size(); ++i) {
      if (!(depth[i] < 1e9f)) continue;
      squared += (pa[i] - pb[i]) * static_cast<double>(pa[i] - pb[i]);
      sum += pb[i];
      ++n;
    }
  }
  return std::sqrt(squared / n) / (sum / n);
}

}  // namespace cli_test

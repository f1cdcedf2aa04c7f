#include "csv.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

namespace yawdepth {

namespace {

namespace fs = std::filesystem;

/* The process umask, read without changing it (umask(2) would race with other threads). */
mode_t currentUmask()
{
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("Umask:", 0) == 0) {
      try {
        return static_cast<mode_t>(std::stoul(line.substr(6), nullptr, 8)) & 0777;
      } catch (...) {
        break;
      }
    }
  }
  return 022;
}

std::string errnoText(int err) { return std::strerror(err); }

/* Removes the temporary file unless released. */
struct TempGuard {
  std::string path;
  int fd = -1;
  ~TempGuard()
  {
    if (fd >= 0)
      ::close(fd);
    if (!path.empty())
      ::unlink(path.c_str());
  }
};

} // namespace

void writeFileAtomically(const std::string &path, const std::string &contents)
{
  using io_detail::throwError;
  if (path.empty())
    throwError("(empty file name): cannot write");
  const fs::path target(path);
  if (!target.has_filename())
    throwError(path + ": not a file name");
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");

  // Mode of the result: that of the file it replaces, else 0666 less the umask.
  mode_t mode = 0666 & ~currentUmask();
  struct stat st;
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode))
      throwError(path + ": is a folder");
    mode = st.st_mode & 07777;
  }

  TempGuard tmp;
  std::string templ = (dir / ("." + target.filename().string() + ".tmpXXXXXX")).string();
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  tmp.fd = ::mkstemp(buf.data());
  if (tmp.fd < 0)
    throwError(path + ": cannot create a temporary file in '" + dir.string() + "' (" + errnoText(errno) + ")");
  tmp.path = buf.data();

  const char *p = contents.data();
  std::size_t left = contents.size();
  while (left > 0) {
    const ssize_t n = ::write(tmp.fd, p, left);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      throwError(path + ": cannot write (" + errnoText(errno) + ")");
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  if (::fchmod(tmp.fd, mode) != 0)
    throwError(path + ": cannot set permissions (" + errnoText(errno) + ")");
  if (::fsync(tmp.fd) != 0)
    throwError(path + ": cannot flush to disk (" + errnoText(errno) + ")");
  const int fd = tmp.fd;
  tmp.fd = -1;
  if (::close(fd) != 0)
    throwError(path + ": cannot close (" + errnoText(errno) + ")");
  if (::rename(tmp.path.c_str(), path.c_str()) != 0)
    throwError(path + ": cannot replace (" + errnoText(errno) + ")");
  tmp.path.clear(); // renamed: nothing to remove

  // Make the rename itself durable; a failure here does not undo a complete file.
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (dfd >= 0) {
    (void)::fsync(dfd);
    ::close(dfd);
  }
}

} // namespace yawdepth

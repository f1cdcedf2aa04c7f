// Inputs read with bounds: regular files and pipes only, line and size limits (files.h).
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

#include "fail.h"

namespace yawdepth {

namespace {

using core_detail::fail;

std::string shown(const std::string &path) { return path.empty() ? std::string("(empty file name)") : path; }

std::string sizeText(std::size_t bytes)
{
  if (bytes >= (std::size_t(1) << 20) && bytes % (std::size_t(1) << 20) == 0)
    return std::to_string(bytes >> 20) + " MiB";
  return std::to_string(bytes) + " bytes";
}

const char *kindOf(mode_t mode)
{
  if (S_ISDIR(mode))
    return "a folder";
  if (S_ISCHR(mode))
    return "a character device";
  if (S_ISBLK(mode))
    return "a block device";
  if (S_ISSOCK(mode))
    return "a socket";
  return "not a regular file";
}

/* Opens `path` for reading once it is known to be a regular file or a FIFO. */
int openInput(const std::string &path)
{
  checkInputFile(path);
  int fd;
  do {
    fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY);
  } while (fd < 0 && errno == EINTR);
  if (fd < 0)
    fail(path + ": cannot open (" + std::strerror(errno) + ")");
  // The file may have been swapped between stat() and open(): check what was opened.
  struct stat st;
  if (::fstat(fd, &st) != 0 || !(S_ISREG(st.st_mode) || S_ISFIFO(st.st_mode))) {
    ::close(fd);
    fail(path + ": cannot read: not a regular file or a pipe");
  }
  return fd;
}

} // namespace

void checkInputFile(const std::string &path)
{
  if (path.empty())
    fail("(empty file name): cannot open");
  struct stat st;
  if (::stat(path.c_str(), &st) != 0)
    fail(path + ": cannot open (" + std::strerror(errno) + ")");
  if (S_ISREG(st.st_mode) || S_ISFIFO(st.st_mode))
    return;
  if (S_ISDIR(st.st_mode))
    fail(path + ": cannot read: is a folder, not a file");
  fail(path + ": cannot read: is " + kindOf(st.st_mode) + ", not a regular file or a pipe");
}

TextInput::TextInput(const std::string &path, const InputLimits &limits) : path_(path), limits_(limits)
{
  fd_ = openInput(path);
  buffer_.resize(std::size_t(1) << 16);
}

TextInput::~TextInput()
{
  if (fd_ >= 0)
    ::close(fd_);
}

/* Reads more bytes after end_ (moving the unread part to the front first); false at the end. */
bool TextInput::fill()
{
  if (eof_)
    return false;
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  if (end_ == buffer_.size())
    buffer_.resize(buffer_.size() * 2);
  ssize_t n;
  do {
    n = ::read(fd_, buffer_.data() + end_, buffer_.size() - end_);
  } while (n < 0 && errno == EINTR);
  if (n < 0)
    fail(path_ + ": cannot read (" + std::strerror(errno) + ")");
  if (n == 0) {
    eof_ = true;
    return false;
  }
  total_ += static_cast<std::size_t>(n);
  if (total_ > limits_.max_bytes)
    fail(path_ + ": larger than " + sizeText(limits_.max_bytes) +
         " (the limit for this input; an endless input such as a device is refused)");
  end_ += static_cast<std::size_t>(n);
  return true;
}

bool TextInput::getline(std::string &line)
{
  std::size_t offset = 0; // bytes after begin_ already searched for '\n'
  for (;;) {
    const void *nl = std::memchr(buffer_.data() + begin_ + offset, '\n', end_ - begin_ - offset);
    if (nl) {
      const std::size_t at = static_cast<std::size_t>(static_cast<const char *>(nl) - buffer_.data());
      if (at - begin_ > limits_.max_line_bytes)
        fail(path_ + ":" + std::to_string(line_number_ + 1) + ": line longer than " +
             sizeText(limits_.max_line_bytes));
      line.assign(buffer_.data() + begin_, at - begin_);
      begin_ = at + 1;
      ++line_number_;
      return true;
    }
    offset = end_ - begin_;
    if (offset > limits_.max_line_bytes)
      fail(path_ + ":" + std::to_string(line_number_ + 1) + ": line longer than " +
           sizeText(limits_.max_line_bytes) + " (not a text file of lines?)");
    if (!fill()) { // fill() keeps the unread bytes, moved to the front: offset stays valid
      if (end_ == begin_)
        return false;
      line.assign(buffer_.data() + begin_, end_ - begin_); // a last line without '\n'
      begin_ = end_;
      ++line_number_;
      return true;
    }
  }
}

std::string TextInput::readAll()
{
  std::string out(buffer_.data() + begin_, end_ - begin_);
  begin_ = end_ = 0;
  while (fill()) {
    out.append(buffer_.data(), end_);
    end_ = 0;
  }
  return out;
}

std::string readTextFile(const std::string &path, std::size_t max_bytes)
{
  InputLimits limits;
  limits.max_bytes = max_bytes;
  TextInput in(path, limits);
  return in.readAll();
}

std::vector<unsigned char> readBinaryFile(const std::string &path, std::size_t max_bytes)
{
  const std::string bytes = readTextFile(path, max_bytes);
  if (bytes.empty())
    fail(shown(path) + ": empty file");
  return std::vector<unsigned char>(bytes.begin(), bytes.end());
}

bool sameFile(const std::string &a, const std::string &b)
{
  struct stat sa, sb;
  if (a.empty() || b.empty() || ::stat(a.c_str(), &sa) != 0 || ::stat(b.c_str(), &sb) != 0)
    return false;
  return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

} // namespace yawdepth

// Outputs written atomically, never over an input, a device or a read-only file (files.h).
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <utility>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

#include "fail.h"

namespace yawdepth {

namespace {

namespace fs = std::filesystem;

using core_detail::fail;

std::string errnoText(int err) { return std::strerror(err); }

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

// ---- temporary files in progress, removed by the signal handler --------------------------------

constexpr int kSlots = 64;
constexpr std::size_t kSlotPath = 4096;
char g_temp_paths[kSlots][kSlotPath];
std::atomic<int> g_temp_state[kSlots]; // 0 free, 1 being filled in, 2 a file to remove on a signal

int registerTemp(const std::string &path)
{
  if (path.size() >= kSlotPath)
    return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (g_temp_state[i].compare_exchange_strong(expected, 1)) {
      std::memcpy(g_temp_paths[i], path.c_str(), path.size() + 1);
      g_temp_state[i].store(2);
      return i;
    }
  }
  return -1; // more than kSlots writes at once: no cleanup on a signal for this one
}

void unregisterTemp(int slot)
{
  if (slot >= 0)
    g_temp_state[slot].store(0);
}

extern "C" void removeTempsAndDie(int sig)
{
  for (int i = 0; i < kSlots; ++i)
    if (g_temp_state[i].load() == 2)
      ::unlink(g_temp_paths[i]); // async-signal-safe
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

bool writeAll(int fd, const std::string &contents)
{
  const char *p = contents.data();
  std::size_t left = contents.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      return false;
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  return true;
}

/* Removes a temporary file (and its signal registration) unless released. */
struct TempFile {
  std::string path;
  int fd = -1;
  int slot = -1;
  ~TempFile()
  {
    if (fd >= 0)
      ::close(fd);
    if (!path.empty())
      ::unlink(path.c_str());
    unregisterTemp(slot);
  }
};

/* Identity of an output for checkOutputs(): device and inode when it exists, else its absolute,
   normalised path (symbolic links in the existing part resolved). Empty for a character device. */
std::string outputKey(const std::string &path)
{
  struct stat st;
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISCHR(st.st_mode))
      return {};
    return "inode:" + std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
  }
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec)
    p = fs::absolute(path, ec).lexically_normal();
  return "path:" + p.string();
}

} // namespace

void checkOutputs(const std::vector<NamedPath> &inputs, const std::vector<NamedPath> &outputs)
{
  // Each input stat'ed once, by (device, inode): a sequence's thousands of images against as many
  // --debug-dir pictures stay linear, not a stat per pair.
  std::map<std::pair<dev_t, ino_t>, const NamedPath *> input_ids;
  for (const NamedPath &i : inputs) {
    struct stat si;
    if (!i.path.empty() && ::stat(i.path.c_str(), &si) == 0)
      input_ids.emplace(std::make_pair(si.st_dev, si.st_ino), &i);
  }
  std::map<std::string, const NamedPath *> seen;
  for (const NamedPath &o : outputs) {
    if (o.path == "-")
      fail(o.option + " -: standard output cannot take this output ('-' is not a file name here; for a file named "
                      "'-', give ./-)");
    if (o.path.empty())
      fail(o.option + ": empty file name");
    struct stat st;
    const bool exists = ::stat(o.path.c_str(), &st) == 0;
    if (exists && S_ISDIR(st.st_mode))
      fail(o.option + " " + o.path + ": is a folder, not a file");
    if (exists) {
      const auto in = input_ids.find(std::make_pair(st.st_dev, st.st_ino));
      if (in != input_ids.end())
        fail(o.option + " " + o.path + ": is the input " + in->second->option + " " + in->second->path +
             " (refusing to overwrite an input; choose another output)");
    }
    const std::string key = outputKey(o.path);
    if (key.empty())
      continue;
    const auto [it, inserted] = seen.emplace(key, &o);
    if (!inserted)
      fail(o.option + " " + o.path + " and " + it->second->option + " " + it->second->path +
           " are the same file (each output needs its own)");
  }
}

AtomicFiles::~AtomicFiles()
{
  for (const Entry &e : entries_) {
    if (!e.temp.empty())
      ::unlink(e.temp.c_str());
    unregisterTemp(e.slot);
  }
}

void AtomicFiles::add(const std::string &path, const std::string &contents)
{
  if (path.empty())
    fail("(empty file name): cannot write");
  Entry e;
  e.shown = path;
  e.target = path;
  struct stat st;
  if (::stat(path.c_str(), &st) == 0 && (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode))) {
    // A device or a pipe, possibly through a link (/dev/stdout to a pipe): written through at
    // commit(), by the path as given, never replaced by a regular file.
    if (::access(path.c_str(), W_OK) != 0)
      fail(path + ": cannot write (" + errnoText(errno) + ")");
    e.contents = contents;
    entries_.push_back(std::move(e));
    return;
  }
  struct stat lst;
  if (::lstat(path.c_str(), &lst) == 0 && S_ISLNK(lst.st_mode)) {
    // A symbolic link is followed on purpose: the file it points to is replaced, the link stays.
    char resolved[PATH_MAX];
    if (!::realpath(path.c_str(), resolved))
      fail(path + ": a symbolic link to a missing file or folder (" + errnoText(errno) + "): not written");
    e.target = resolved;
  }
  const fs::path target(e.target);
  if (!target.has_filename() || target.filename() == "." || target.filename() == "..")
    fail(path + ": not a file name");
  for (const Entry &other : entries_)
    if (other.target == e.target)
      fail(path + ": written twice in one commit");

  mode_t mode = 0666 & ~currentUmask();
  if (::stat(e.target.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode))
      fail(path + ": is a folder, not a file");
    if (!S_ISREG(st.st_mode))
      fail(path + ": is not a regular file, a character device or a pipe: not written");
    // Read-only stays read-only, for root too (access() would let root through).
    if ((st.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) == 0 || ::access(e.target.c_str(), W_OK) != 0)
      fail(path + ": is read-only: not replaced (make it writable or choose another output)");
    mode = st.st_mode & 07777;
  }

  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  TempFile tmp;
  // `.NAME.tmpXXXXXX` beside the target, or `.yawdepth.tmpXXXXXX` when that would not fit in the
  // folder's longest file name (a target's name of 245 characters or more, on most file systems).
  const long name_max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  const std::string beside = "." + target.filename().string() + ".tmpXXXXXX";
  const std::string templ =
      (dir / (beside.size() <= static_cast<std::size_t>(name_max > 0 ? name_max : NAME_MAX) ? beside
                                                                                           : ".yawdepth.tmpXXXXXX"))
          .string();
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  tmp.fd = ::mkstemp(buf.data());
  if (tmp.fd < 0)
    fail(path + ": cannot create a temporary file in '" + dir.string() + "' (" + errnoText(errno) + ")");
  tmp.path = buf.data();
  tmp.slot = registerTemp(tmp.path);
  if (!writeAll(tmp.fd, contents))
    fail(path + ": cannot write (" + errnoText(errno) + ")");
  if (::fchmod(tmp.fd, mode) != 0)
    fail(path + ": cannot set permissions (" + errnoText(errno) + ")");
  if (::fsync(tmp.fd) != 0)
    fail(path + ": cannot flush to disk (" + errnoText(errno) + ")");
  const int fd = tmp.fd;
  tmp.fd = -1;
  if (::close(fd) != 0)
    fail(path + ": cannot close (" + errnoText(errno) + ")");
  // The entry owns the file now; it stays registered for the signal handler until commit().
  e.temp = tmp.path;
  e.slot = tmp.slot;
  entries_.push_back(std::move(e));
  tmp.path.clear();
  tmp.slot = -1;
}

void AtomicFiles::commit()
{
  // Devices and pipes first: a write error there (a full disk, /dev/full) leaves every regular
  // target untouched.
  for (Entry &e : entries_) {
    if (!e.temp.empty())
      continue;
    int fd;
    do {
      fd = ::open(e.target.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
    } while (fd < 0 && errno == EINTR);
    if (fd < 0)
      fail(e.shown + ": cannot open for writing (" + errnoText(errno) + ")");
    const bool ok = writeAll(fd, e.contents);
    const int err = errno;
    const bool closed = ::close(fd) == 0;
    if (!ok)
      fail(e.shown + ": cannot write (" + errnoText(err) + ")");
    if (!closed)
      fail(e.shown + ": cannot write (" + errnoText(errno) + ")");
    e.contents.clear();
  }
  std::vector<std::string> dirs;
  for (Entry &e : entries_) {
    if (e.temp.empty())
      continue;
    if (::rename(e.temp.c_str(), e.target.c_str()) != 0)
      fail(e.shown + ": cannot replace (" + errnoText(errno) + ")");
    unregisterTemp(e.slot);
    e.slot = -1;
    e.temp.clear();
    const fs::path t(e.target);
    dirs.push_back(t.has_parent_path() ? t.parent_path().string() : std::string("."));
  }
  // Make the renames durable; a failure here does not undo complete files.
  for (const std::string &d : dirs) {
    const int dfd = ::open(d.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
      (void)::fsync(dfd);
      ::close(dfd);
    }
  }
  entries_.clear();
}

void writeFileAtomically(const std::string &path, const std::string &contents)
{
  AtomicFiles files;
  files.add(path, contents);
  files.commit();
}

ScratchFile::ScratchFile(const std::string &suffix)
{
  const char *dir = std::getenv("TMPDIR");
  std::string templ = std::string(dir && *dir ? dir : "/tmp") + "/yawdepth-XXXXXX" + suffix;
  const int fd = ::mkstemps(templ.data(), static_cast<int>(suffix.size()));
  if (fd < 0)
    throw Error("cannot create a scratch file " + templ + ": " + std::strerror(errno));
  ::close(fd);
  path_ = templ;
  slot_ = registerTemp(path_);
}

ScratchFile::~ScratchFile()
{
  ::unlink(path_.c_str());
  unregisterTemp(slot_);
}

void removeTemporaryFilesOnSignals()
{
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old;
    if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler != SIG_DFL || (old.sa_flags & SA_SIGINFO))
      continue; // the program has its own handler, or ignores the signal (nohup): keep that
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = removeTempsAndDie;
    sigemptyset(&sa.sa_mask);
    ::sigaction(sig, &sa, nullptr);
  }
}

} // namespace yawdepth

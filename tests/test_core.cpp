// core: bounded inputs, outputs that never replace an input, a device or a read-only file, and
// commits that are all or nothing (yawdepth/core/files.h).
#include <catch2/catch.hpp>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

#include "file_support.h"

using namespace yawdepth;
using namespace yawdepth::test;
namespace fs = std::filesystem;

namespace {

bool contains(const std::string &text, const std::string &part) { return text.find(part) != std::string::npos; }

} // namespace

TEST_CASE("inputs: only regular files and pipes are read", "[core][files]")
{
  TempDir dir;
  const std::string ok = dir.write("ok.csv", "a\n");
  CHECK_NOTHROW(checkInputFile(ok));
  CHECK(contains(errorOf([&] { checkInputFile(dir.path.string()); }), "is a folder"));
  CHECK(contains(errorOf([&] { checkInputFile("/dev/zero"); }), "/dev/zero: cannot read: is a character device"));
  CHECK(contains(errorOf([&] { checkInputFile(dir.file("missing")); }), "No such file"));
  CHECK(contains(errorOf([&] { checkInputFile(""); }), "empty file name"));
  // A symbolic link to a device is the device.
  fs::create_symlink("/dev/urandom", dir.file("image.png"));
  CHECK(contains(errorOf([&] { readBinaryFile(dir.file("image.png"), 1000); }), "character device"));
  // The error is one line, even for a path with a newline in it.
  const std::string odd = dir.file("a\nb");
  CHECK(errorOf([&] { checkInputFile(odd); }).find('\n') == std::string::npos);

  // A FIFO is read as a stream, however long the writer takes.
  const std::string fifo = dir.file("fifo");
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  std::thread writer([&] { std::ofstream(fifo) << "frame\n1\n2"; });
  TextInput in(fifo);
  std::string line;
  std::vector<std::string> lines;
  while (in.getline(line))
    lines.push_back(line);
  writer.join();
  CHECK(lines == std::vector<std::string>{"frame", "1", "2"});
}

TEST_CASE("inputs: lines and sizes are bounded", "[core][files]")
{
  TempDir dir;
  const std::string p = dir.write("lines.txt", "one\r\ntwo\n\nlast");
  TextInput in(p);
  std::string line;
  REQUIRE(in.getline(line));
  CHECK(line == "one\r"); // the CR is the caller's to strip
  REQUIRE(in.getline(line));
  CHECK(line == "two");
  REQUIRE(in.getline(line));
  CHECK(line.empty());
  REQUIRE(in.getline(line));
  CHECK(line == "last");
  CHECK(in.lineNumber() == 4);
  CHECK_FALSE(in.getline(line));

  // Lines across the reader's 64 KiB buffer are whole.
  std::string many;
  for (int i = 0; i < 30000; ++i)
    many += std::to_string(i) + "\n";
  const std::string pm = dir.write("many.txt", many);
  TextInput im(pm);
  int n = 0;
  bool ordered = true;
  while (im.getline(line))
    ordered = ordered && line == std::to_string(n++);
  CHECK(n == 30000);
  CHECK(ordered);
  CHECK(readTextFile(pm, 1u << 20) == many);

  InputLimits limits;
  limits.max_line_bytes = 10;
  const std::string pl = dir.write("long.txt", "short\n0123456789abc\n");
  TextInput il(pl, limits);
  REQUIRE(il.getline(line));
  CHECK(contains(errorOf([&] { il.getline(line); }), pl + ":2: line longer than 10 bytes"));

  limits = InputLimits();
  limits.max_bytes = 1000;
  CHECK(contains(errorOf([&] { readTextFile(pm, limits.max_bytes); }), pm + ": larger than 1000 bytes"));
  CHECK(contains(errorOf([&] { readBinaryFile(dir.write("empty", ""), 10); }), "empty file"));
}

TEST_CASE("outputs: never an input, never twice", "[core][files]")
{
  TempDir dir;
  const std::string tracks = dir.write("t.csv", "frame,id,u,v\n");
  const std::string motion = dir.write("m.csv", "frame\n");
  fs::create_hard_link(tracks, dir.file("hard.csv"));
  fs::create_symlink(tracks, dir.file("soft.csv"));
  const std::vector<NamedPath> inputs = {{"--motion", motion}, {"--tracks", tracks}};

  CHECK(sameFile(tracks, dir.file("hard.csv")));
  CHECK(sameFile(tracks, dir.file("soft.csv")));
  CHECK_FALSE(sameFile(tracks, motion));
  CHECK_FALSE(sameFile(tracks, dir.file("missing.csv")));

  for (const std::string &out : {tracks, dir.file("hard.csv"), dir.file("soft.csv"), dir.file("./t.csv")}) {
    const std::string m = errorOf([&] { checkOutputs(inputs, {{"--out", out}}); });
    CHECK(contains(m, "--out " + out + ": is the input --tracks " + tracks));
  }
  CHECK_NOTHROW(checkOutputs(inputs, {{"--out", dir.file("points.csv")}, {"--outliers", dir.file("o.csv")}}));
  // Two outputs onto one file, existing or not.
  CHECK(contains(errorOf([&] { checkOutputs(inputs, {{"--out", dir.file("p.csv")}, {"--outliers", dir.file("./p.csv")}}); }),
                 "are the same file"));
  const std::string existing = dir.write("e.csv", "x");
  CHECK(contains(errorOf([&] { checkOutputs(inputs, {{"--out", existing}, {"--tracks-out", existing}}); }),
                 "are the same file"));
  // Devices may repeat; "-" is not a file name (a writer would make a file named "-"), nor is an
  // empty name or a folder.
  CHECK_NOTHROW(checkOutputs(inputs, {{"--out", "/dev/null"}, {"--outliers", "/dev/null"}}));
  CHECK(contains(errorOf([&] { checkOutputs(inputs, {{"--ply", "-"}}); }),
                 "--ply -: standard output cannot take this output"));
  CHECK_NOTHROW(checkOutputs(inputs, {{"--ply", "./-"}}));
  CHECK(contains(errorOf([&] { checkOutputs(inputs, {{"--out", ""}}); }), "--out: empty file name"));
  CHECK(contains(errorOf([&] { checkOutputs(inputs, {{"--out", dir.path.string()}}); }), "is a folder"));
  // The input is untouched by any of it.
  CHECK(slurp(tracks) == "frame,id,u,v\n");
}

TEST_CASE("outputs: atomic, through links and devices, never over a read-only file", "[core][files]")
{
  TempDir dir;
  const std::string p = dir.file("out.csv");
  writeFileAtomically(p, "one\n");
  CHECK(slurp(p) == "one\n");
  ::chmod(p.c_str(), 0640);
  writeFileAtomically(p, "two\n");
  CHECK(slurp(p) == "two\n");
  CHECK((fs::status(p).permissions() & fs::perms::all) == (fs::perms::owner_read | fs::perms::owner_write |
                                                           fs::perms::group_read)); // mode kept
  CHECK(dir.temporaries().empty());

  // A symbolic link is followed: its target is replaced, the link stays a link.
  fs::create_symlink("out.csv", dir.file("link.csv"));
  writeFileAtomically(dir.file("link.csv"), "three\n");
  CHECK(fs::is_symlink(dir.file("link.csv")));
  CHECK(slurp(p) == "three\n");
  fs::create_symlink("nowhere/x.csv", dir.file("dangling.csv"));
  CHECK(contains(errorOf([&] { writeFileAtomically(dir.file("dangling.csv"), "x"); }), "symbolic link to a missing"));

  // A read-only file stays as it is (for root too).
  const std::string ro = dir.write("ro.csv", "keep\n");
  ::chmod(ro.c_str(), 0444);
  CHECK(contains(errorOf([&] { writeFileAtomically(ro, "lost\n"); }), ro + ": is read-only: not replaced"));
  CHECK(slurp(ro) == "keep\n");

  // Devices are written through and stay devices.
  writeFileAtomically("/dev/null", "nothing\n");
  CHECK(fs::is_character_file("/dev/null"));
  REQUIRE(fs::is_character_file("/dev/full")); // Linux's always-full device
  CHECK(contains(errorOf([&] { writeFileAtomically("/dev/full", "x"); }), "/dev/full: cannot write (No space left"));
  CHECK(fs::is_character_file("/dev/full"));

  // Bad names.
  CHECK(contains(errorOf([&] { writeFileAtomically("", "x"); }), "empty file name"));
  CHECK(contains(errorOf([&] { writeFileAtomically(dir.path.string(), "x"); }), "is a folder"));
  CHECK(contains(errorOf([&] { writeFileAtomically(dir.file("no/such/folder/x.csv"), "x"); }),
                 "cannot create a temporary file"));
  CHECK(dir.temporaries().empty());

  // Names up to the file system's longest (255 bytes): the temporary file's name fits too.
  for (const std::size_t length : {244, 245, 250, 255}) {
    const std::string name = dir.file(std::string(length - 4, 'n') + ".csv");
    writeFileAtomically(name, "long\n");
    CHECK(slurp(name) == "long\n");
    writeFileAtomically(name, "again\n"); // replacing it too
    CHECK(slurp(name) == "again\n");
  }
  CHECK(contains(errorOf([&] { writeFileAtomically(dir.file(std::string(256, 'n')), "x"); }), "cannot"));
  CHECK(dir.temporaries().empty());
}

TEST_CASE("outputs: files committed together are all or nothing", "[core][files]")
{
  TempDir dir;
  const std::string yaml = dir.write("cam.yaml", "old yaml");
  fs::create_directory(dir.file("cam.xml")); // the second target cannot be written
  {
    AtomicFiles files;
    files.add(yaml, "new yaml");
    CHECK(contains(errorOf([&] { files.add(dir.file("cam.xml"), "new xml"); }), "is a folder"));
  } // not committed: the staged file is removed
  CHECK(slurp(yaml) == "old yaml");
  CHECK(dir.temporaries().empty());

  // A device that fails is written first: the regular files are not replaced.
  {
    AtomicFiles files;
    files.add(yaml, "new yaml");
    files.add("/dev/full", "x");
    CHECK_THROWS_AS(files.commit(), Error);
  }
  CHECK(slurp(yaml) == "old yaml");
  CHECK(dir.temporaries().empty());

  AtomicFiles files;
  files.add(yaml, "new yaml");
  files.add(dir.file("cam2.xml"), "new xml");
  CHECK(contains(errorOf([&] { files.add(yaml, "again"); }), "written twice"));
  files.commit();
  CHECK(slurp(yaml) == "new yaml");
  CHECK(slurp(dir.file("cam2.xml")) == "new xml");
  CHECK(dir.temporaries().empty());
}

TEST_CASE("outputs: a signal during a write leaves no temporary file", "[core][files]")
{
  TempDir dir;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      // The child stages a large file, then is interrupted before the commit. (Catch2 has its own
      // handlers, which removeTemporaryFilesOnSignals() would respect: back to the defaults.)
      for (const int s : {SIGINT, SIGTERM, SIGHUP})
        ::signal(s, SIG_DFL);
      removeTemporaryFilesOnSignals();
      AtomicFiles files;
      files.add(dir.file("big.csv"), std::string(4u << 20, 'x'));
      ::raise(sig);
      ::_exit(0); // not reached: the handler ends the process by the signal
    }
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    CHECK(WIFSIGNALED(status));
    CHECK(WTERMSIG(status) == sig);
    CHECK(dir.temporaries().empty());
    CHECK_FALSE(fs::exists(dir.file("big.csv")));
  }
}

#pragma once
// Test support for the tests of files (test_core, test_io): a temporary folder, a file's bytes,
// and the message of the yawdepth::Error a call throws.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>
#include <stdlib.h> // mkdtemp
#include <yawdepth/error.h>

namespace yawdepth {
namespace test {

/* A fresh folder under the system's temporary folder, removed with its contents (even when a test
   left it or a file in it read-only). */
struct TempDir {
  std::filesystem::path path;
  TempDir()
  {
    std::string templ = (std::filesystem::temp_directory_path() / "yawdepth_test_XXXXXX").string();
    REQUIRE(::mkdtemp(templ.data()) != nullptr);
    path = templ;
  }
  ~TempDir()
  {
    std::error_code ec;
    std::filesystem::permissions(path, std::filesystem::perms::owner_all, std::filesystem::perm_options::add, ec);
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir &) = delete;
  TempDir &operator=(const TempDir &) = delete;
  std::string file(const std::string &name) const { return (path / name).string(); }
  /* Write raw bytes to `name` and return its path. */
  std::string write(const std::string &name, const std::string &bytes) const
  {
    const std::string p = file(name);
    std::ofstream f(p, std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return p;
  }
  /* Number of entries in the folder. */
  std::size_t count() const
  {
    std::size_t n = 0;
    for (auto it = std::filesystem::directory_iterator(path); it != std::filesystem::directory_iterator(); ++it)
      ++n;
    return n;
  }
  /* Names of the hidden temporary files left in the folder. */
  std::vector<std::string> temporaries() const
  {
    std::vector<std::string> out;
    for (const auto &e : std::filesystem::directory_iterator(path))
      if (e.path().filename().string().find(".tmp") != std::string::npos)
        out.push_back(e.path().filename().string());
    return out;
  }
};

/* The whole contents of a file. */
inline std::string slurp(const std::string &path)
{
  std::ifstream f(path, std::ios::binary);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/* The message of the yawdepth::Error thrown by `f` (a test failure when there is none). */
inline std::string errorOf(const std::function<void()> &f)
{
  try {
    f();
  } catch (const Error &e) {
    return e.what();
  } catch (const std::exception &e) {
    FAIL("not a yawdepth::Error: " << e.what());
  }
  FAIL("no error thrown");
  return {};
}

} // namespace test
} // namespace yawdepth

// rosbag2's SQLite storage (.db3): tables topics(id, name, type, serialization_format, ...) and
// messages(id, topic_id, timestamp, data), read-only, one row at a time, in timestamp order.
#include "readers.h"

#include <map>
#include <sqlite3.h>
#include <yawdepth/error.h>

namespace yawdepth {
namespace bag_detail {

namespace {

/* One .db3 file, opened read-only. */
class Db {
public:
  explicit Db(const std::string &path) : path_(path)
  {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      const std::string e = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw Error(path + ": cannot open the SQLite database: " + e);
    }
  }
  ~Db() { sqlite3_close(db_); }
  Db(const Db &) = delete;
  Db &operator=(const Db &) = delete;

  [[noreturn]] void fail(const std::string &what) const
  {
    throw Error(path_ + ": " + what + ": " + sqlite3_errmsg(db_) + " (not a readable rosbag2 database)");
  }
  const std::string &path() const { return path_; }
  sqlite3 *get() const { return db_; }

private:
  std::string path_;
  sqlite3 *db_ = nullptr;
};

/* A prepared statement, finalized on scope exit. */
class Statement {
public:
  Statement(const Db &db, const std::string &sql) : db_(db)
  {
    if (sqlite3_prepare_v2(db.get(), sql.c_str(), -1, &s_, nullptr) != SQLITE_OK)
      db.fail("cannot query it");
  }
  ~Statement() { sqlite3_finalize(s_); }
  Statement(const Statement &) = delete;
  Statement &operator=(const Statement &) = delete;
  /* The next row: true, or false at the end. */
  bool step()
  {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW)
      return true;
    if (rc == SQLITE_DONE)
      return false;
    db_.fail("reading it failed");
  }
  void bind(int i, std::int64_t v) { sqlite3_bind_int64(s_, i, v); }
  std::int64_t i64(int c) const { return sqlite3_column_int64(s_, c); }
  std::string text(int c) const
  {
    const unsigned char *t = sqlite3_column_text(s_, c);
    return t ? std::string(reinterpret_cast<const char *>(t), std::size_t(sqlite3_column_bytes(s_, c))) : std::string();
  }
  sqlite3_stmt *get() const { return s_; }

private:
  const Db &db_;
  sqlite3_stmt *s_ = nullptr;
};

struct Db3File {
  std::unique_ptr<Db> db;
  std::map<std::int64_t, std::size_t> topics; // topics.id -> topic index
};

class Db3Reader final : public BagReader {
public:
  Db3Reader(std::string path, const std::vector<std::string> &files) : path_(std::move(path))
  {
    for (const std::string &p : files) {
      Db3File f;
      f.db = std::make_unique<Db>(p);
      open(f);
      files_.push_back(std::move(f));
    }
  }

  BagFormat format() const override { return BagFormat::Sqlite3; }
  const std::string &path() const override { return path_; }
  const std::vector<BagTopic> &topics() const override { return topics_; }

  void read(const BagReadOptions &options, const std::function<bool(const BagMessage &)> &visit) override
  {
    for (Db3File &f : files_) {
      std::string sql = "SELECT topic_id, timestamp, data FROM messages WHERE timestamp >= ?1 AND timestamp <= ?2";
      if (!options.topics.empty()) {
        std::string ids;
        for (const auto &t : f.topics)
          for (const std::string &name : options.topics)
            if (topics_[t.second].name == name)
              ids += (ids.empty() ? "" : ",") + std::to_string(t.first);
        if (ids.empty())
          continue;
        sql += " AND topic_id IN (" + ids + ")";
      }
      sql += " ORDER BY timestamp, id";
      Statement s(*f.db, sql);
      s.bind(1, options.start);
      s.bind(2, options.end);
      while (s.step()) {
        const auto t = f.topics.find(s.i64(0));
        if (t == f.topics.end())
          throw Error(f.db->path() + ": a message on topic id " + std::to_string(s.i64(0)) +
                      ", which the topics table does not have");
        BagMessage m;
        m.topic = &topics_[t->second];
        m.log_time = s.i64(1);
        m.data = static_cast<const std::uint8_t *>(sqlite3_column_blob(s.get(), 2));
        m.size = std::size_t(sqlite3_column_bytes(s.get(), 2));
        if (!visit(m))
          return;
      }
    }
  }

private:
  void open(Db3File &f)
  {
    const Db &db = *f.db;
    {
      Statement s(db, "SELECT name FROM sqlite_master WHERE type = 'table' AND name IN ('topics', 'messages')");
      int n = 0;
      while (s.step())
        ++n;
      if (n != 2)
        throw Error(db.path() + ": an SQLite database without rosbag2's topics and messages tables (not a rosbag2 bag)");
    }
    {
      Statement s(db, "SELECT id, name, type, serialization_format FROM topics ORDER BY id");
      while (s.step()) {
        const std::string name = s.text(1), format = s.text(3);
        std::string type = s.text(2);
        if (format != "cdr")
          throw Error(db.path() + ": topic " + name + " is serialized as '" + format + "', not cdr");
        const std::size_t m = type.find("/msg/");
        if (m != std::string::npos)
          type.erase(m, 4);
        std::size_t i = 0;
        while (i < topics_.size() && topics_[i].name != name)
          ++i;
        if (i == topics_.size()) {
          BagTopic t;
          t.name = name;
          t.type = type;
          t.encoding = BagEncoding::Cdr;
          topics_.push_back(t);
        }
        f.topics[s.i64(0)] = i;
      }
    }
    {
      Statement s(db, "SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id");
      while (s.step()) {
        const auto t = f.topics.find(s.i64(0));
        if (t != f.topics.end())
          topics_[t->second].messages += std::uint64_t(s.i64(1));
      }
    }
  }

  std::string path_;
  std::vector<Db3File> files_;
  std::vector<BagTopic> topics_;
};

} // namespace

std::unique_ptr<BagReader> openDb3(const std::string &path, const std::vector<std::string> &files)
{
  return std::make_unique<Db3Reader>(path, files);
}

} // namespace bag_detail
} // namespace yawdepth

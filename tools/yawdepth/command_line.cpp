#include "command_line.h"

#include "commands.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace yawdepth::cli {

namespace {

/* A word that is a value although it begins with a dash: a number or a list of them (--yaw -0.5,
   --time-offset-range -0.1,0.1: a digit or a point after the dash, as CLI11 takes it), or standard
   input/output ("-"). */
bool isValue(const std::string &word)
{
  return word.size() < 2 || word[0] != '-' || std::isdigit(static_cast<unsigned char>(word[1])) || word[1] == '.';
}

/* The option named by a word (--name=value: --name). */
std::string optionName(const std::string &word) { return word.substr(0, word.find('=')); }

std::size_t editDistance(const std::string &a, const std::string &b)
{
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j)
    row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

/* The closest of `names` to `typed` (both without dashes) when close: at most 2 edits (1 for a name
   of 4 letters or fewer), or the shortest name `typed` begins (3 letters or more). Empty otherwise. */
std::string closest(const std::string &typed, const std::vector<std::string> &names)
{
  std::string best;
  std::size_t best_distance = typed.size() <= 4 ? 1 : 2;
  for (const std::string &n : names) {
    const std::size_t d = editDistance(typed, n);
    if (d <= best_distance && (best.empty() || d < best_distance)) {
      best = n;
      best_distance = d;
    }
  }
  if (!best.empty() || typed.size() < 3)
    return best;
  for (const std::string &n : names)
    if (n.compare(0, typed.size(), typed) == 0 && (best.empty() || n.size() < best.size()))
      best = n;
  return best;
}

/* The long names of `sub`'s options (without dashes), aliases included. */
std::vector<std::string> longNames(const CLI::App &sub)
{
  std::vector<std::string> names;
  for (const CLI::Option *o : sub.get_options())
    for (const std::string &n : o->get_lnames())
      names.push_back(n);
  return names;
}

/* The options `args` gives (the command line's), to leave out of the settings file. */
std::set<const CLI::Option *> givenOptions(const CLI::App &sub, const std::vector<std::string> &args)
{
  std::set<const CLI::Option *> given;
  for (const std::string &word : args) {
    if (word == "--")
      break;
    if (!isValue(word))
      if (const CLI::Option *o = sub.get_option_no_throw(optionName(word)))
        given.insert(o);
  }
  return given;
}

} // namespace

std::string unknownOption(const CLI::App &sub, const std::vector<std::string> &args)
{
  for (const std::string &word : args) {
    if (word == "--")
      break;
    if (isValue(word))
      continue;
    const std::string name = optionName(word);
    if (sub.get_option_no_throw(name) != nullptr)
      continue;
    std::string text = "unknown option '" + name + "'";
    const std::string typed = name.substr(std::min(name.find_first_not_of('-'), name.size())); // without dashes
    const std::string suggestion = closest(typed, longNames(sub));
    if (!suggestion.empty())
      text += " (did you mean --" + suggestion + "?)";
    return text;
  }
  return {};
}

void warnRenamedOptions(const CLI::App &sub, const std::vector<std::string> &args)
{
  for (const std::string &word : args) {
    if (word == "--")
      break;
    for (const RenamedOption &r : renamedOptions())
      if (r.command == sub.get_name() && !isValue(word) && optionName(word) == r.old_name)
        warn(r.command, r.old_name + " is spelled " + r.new_name + " now (the old name still works)");
  }
}

namespace {

/* The line of `file` where `key` is set (1-based), or 0. */
int lineOf(const std::string &file, const std::string &key)
{
  std::ifstream in(file);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const std::size_t start = line.find_first_not_of(" \t");
    if (start != std::string::npos && line.compare(start, key.size(), key) == 0) {
      const std::size_t after = start + key.size();
      if (after == line.size() || line[after] == ' ' || line[after] == '=' || line[after] == '\t')
        return n;
    }
  }
  return 0;
}

/* FILE:LINE: (or FILE: when the key's line is not found). */
std::string where(const std::string &file, const std::string &key)
{
  const int line = lineOf(file, key);
  return file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": ";
}

/* The words that set `o` to the file's `inputs` (a flag: its name when true). */
std::vector<std::string> settingWords(const CLI::Option &o, const std::string &key, const std::vector<std::string> &inputs,
                                      const std::string &file)
{
  const std::string name = "--" + o.get_lnames().front();
  if (o.get_expected_min() == 0) {
    const std::string v = inputs.empty() ? "true" : inputs.front();
    if (v == "true" || v == "1" || v == "yes" || v == "on")
      return {name};
    if (v == "false" || v == "0" || v == "no" || v == "off")
      return {};
    throw ConfigFileError{where(file, key) + "'" + key + "' is a switch: true or false, not '" + v + "'"};
  }
  if (inputs.size() == 1 || o.get_delimiter() != '\0') {
    std::string joined;
    for (const std::string &v : inputs)
      joined += (joined.empty() ? "" : std::string(1, o.get_delimiter())) + v;
    return {name + "=" + joined};
  }
  std::vector<std::string> words;
  for (const std::string &v : inputs)
    words.push_back(name + "=" + v);
  return words;
}

/* The command of `app` named `name`, or null. */
const CLI::App *findCommand(CLI::App &app, const std::string &name)
{
  for (const CLI::App *c : app.get_subcommands({}))
    if (c->get_name() == name)
      return c;
  return nullptr;
}

/* Whether some command of `app` takes --`key` (a top-level key for another command). */
bool anyCommandHas(CLI::App &app, const std::string &key)
{
  for (const CLI::App *c : app.get_subcommands({}))
    if (c->get_option_no_throw("--" + key) != nullptr)
      return true;
  return false;
}

/* One setting of the file checked against the command line's options: the option of `sub` it sets,
   null when it is for another command. */
const CLI::Option *settingOption(CLI::App &app, const CLI::App &sub, const CLI::ConfigItem &item,
                                 const std::string &key, const std::string &file)
{
  const std::string section = item.parents.empty() ? std::string() : item.parents.front();
  const CLI::App *target = &sub;
  if (!section.empty() && section != sub.get_name()) {
    target = findCommand(app, section);
    if (target == nullptr || item.parents.size() > 1)
      throw ConfigFileError{file + ": [" + section + "] is not a yawdepth command"};
  }
  const CLI::Option *o = target->get_option_no_throw("--" + key);
  if (o == nullptr && section.empty() && anyCommandHas(app, key))
    return nullptr; // another command's setting in a shared file
  if (o == nullptr) {
    const std::string suggestion = closest(key, longNames(*target));
    throw ConfigFileError{where(file, item.name) + "unknown key '" + item.name + "' for yawdepth " +
                          target->get_name() + (suggestion.empty() ? "" : " (did you mean " + suggestion + "?)")};
  }
  if (!o->get_configurable() || o->get_lnames().empty() || key == "help")
    throw ConfigFileError{where(file, item.name) + "'" + item.name + "' cannot be set in a settings file"};
  return target == &sub ? o : nullptr;
}

/* Whether `o` excludes an option the command line gives (--view in the file, --yaw on the line). */
bool excludesGiven(const CLI::Option &o, const std::set<const CLI::Option *> &given)
{
  for (const CLI::Option *x : o.get_excludes())
    if (given.count(x) > 0)
      return true;
  return false;
}

/* --config's value among `args` (empty when not given); an empty name, or an option where the name
   should be (`--config --print-config`), is refused. */
std::string configFile(const std::vector<std::string> &args)
{
  for (std::size_t i = 0; i < args.size() && args[i] != "--"; ++i) {
    std::string file;
    if (args[i].rfind("--config=", 0) == 0)
      file = args[i].substr(9);
    else if (args[i] == "--config" && i + 1 < args.size())
      file = args[i + 1];
    else
      continue;
    if (file.empty() || file.rfind("--", 0) == 0)
      throw ConfigFileError{"--config needs a settings file's name" +
                            (file.empty() ? std::string() : ", not the option " + file)};
    return file;
  }
  return {};
}

/* A value CLI11's reader cut at a '#' (or ';' in INI), which it reads as a comment even inside
   quotes: its opening quote is left unclosed. */
bool cutAtComment(const std::vector<std::string> &inputs)
{
  for (const std::string &v : inputs)
    if (!v.empty() && (v.front() == '"' || v.front() == '\'') && (v.size() == 1 || v.back() != v.front()))
      return true;
  return false;
}

} // namespace

ConfigApplied applyConfigFile(CLI::App &app, const CLI::App &sub, std::vector<std::string> &args)
{
  ConfigApplied applied;
  applied.file = configFile(args);
  if (applied.file.empty())
    return applied;
  const std::string &file = applied.file;
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    throw ConfigFileError{file + ": a folder, not a settings file"};
  std::vector<CLI::ConfigItem> items;
  try {
    const bool ini = file.size() > 4 && file.compare(file.size() - 4, 4, ".ini") == 0;
    items = ini ? CLI::ConfigINI().from_file(file) : CLI::ConfigTOML().from_file(file);
  } catch (const CLI::Error &) {
    throw ConfigFileError{file + ": cannot read the settings file"};
  }
  const std::set<const CLI::Option *> given = givenOptions(sub, args);
  // The settings for this command: a [command] section's key wins over the same top-level key.
  std::map<const CLI::Option *, const CLI::ConfigItem *> chosen;
  std::vector<const CLI::Option *> order;
  for (const CLI::ConfigItem &item : items) {
    if (item.name == "++" || item.name == "--")
      continue; // section markers
    std::string key = item.name;
    std::replace(key.begin(), key.end(), '_', '-');
    const CLI::Option *o = settingOption(app, sub, item, key, file);
    if (o == nullptr || given.count(o) > 0 || excludesGiven(*o, given))
      continue; // the command line overrides the file, also by giving an option this one excludes
    if (cutAtComment(item.inputs))
      throw ConfigFileError{where(file, item.name) + "'" + item.name + "': a value with '#' (or ';' in INI), which " +
                            "a settings file reads as a comment: give it on the command line"};
    const auto at = chosen.find(o);
    if (at == chosen.end()) {
      order.push_back(o);
      chosen[o] = &item;
    } else if (!item.parents.empty()) {
      at->second = &item; // the section's
    }
  }
  // A setting that needs an option neither given nor set (camera-name without camera, when the
  // command line's --kx excluded the file's camera) goes too.
  std::set<const CLI::Option *> present = given;
  for (const CLI::Option *o : order)
    present.insert(o);
  for (bool dropped = true; dropped;) {
    dropped = false;
    for (const CLI::Option *o : order)
      if (present.count(o) > 0 && given.count(o) == 0)
        for (const CLI::Option *n : o->get_needs())
          if (present.count(n) == 0) {
            present.erase(o);
            dropped = true;
            break;
          }
  }
  std::vector<std::string> words;
  for (const CLI::Option *o : order) {
    if (present.count(o) == 0)
      continue;
    for (std::string &w : settingWords(*o, chosen[o]->name, chosen[o]->inputs, file))
      words.push_back(std::move(w));
    applied.options.insert("--" + o->get_lnames().front());
  }
  // Right after the command, so that an option on the line whose value was forgotten cannot take
  // a setting as its value; the command line still wins (its options were left out above).
  args.insert(args.begin(), words.begin(), words.end());
  return applied;
}

namespace {

std::string tomlValue(const std::string &key, const std::string &v)
{
  if (v.find('#') != std::string::npos || (v.find('"') != std::string::npos && v.find('\'') != std::string::npos))
    throw ConfigFileError{"--print-config: the value of --" + key + " (" + v +
                          ") cannot be written in a settings file (a '#' reads as a comment, or both quotes): "
                          "give it on the command line"};
  char *end = nullptr;
  std::strtod(v.c_str(), &end);
  if ((!v.empty() && end != v.c_str() && *end == '\0') || v == "true" || v == "false")
    return v;
  const char quote = v.find('"') == std::string::npos ? '"' : '\'';
  return quote + v + quote;
}

} // namespace

std::string effectiveConfig(const CLI::App &sub)
{
  std::ostringstream out;
  out << "# yawdepth " << sub.get_name() << ": effective settings (read back with: yawdepth " << sub.get_name()
      << " --config FILE); defaults as comments\n";
  for (const CLI::Option *o : sub.get_options()) {
    if (!o->get_configurable() || o->get_lnames().empty() || o->get_lnames().front() == "help" ||
        o->get_lnames().front() == "print-config")
      continue;
    const std::string key = o->get_lnames().front();
    // What is not given keeps its default: shown as a comment (a default printed to 6 digits and
    // read back would not be the default any more).
    const char *prefix = o->count() > 0 ? "" : "# ";
    if (o->get_expected_min() == 0) {
      out << prefix << key << " = " << (o->count() > 0 ? "true" : "false") << "\n";
      continue;
    }
    std::vector<std::string> values = o->results();
    if (o->count() == 0 && !o->get_default_str().empty())
      values = {o->get_default_str()};
    if (values.empty())
      continue;
    out << prefix;
    if (values.size() == 1 && o->get_expected_max() <= 1) {
      out << key << " = " << tomlValue(key, values.front()) << "\n";
      continue;
    }
    out << key << " = [";
    for (std::size_t i = 0; i < values.size(); ++i)
      out << (i ? ", " : "") << tomlValue(key, values[i]);
    out << "]\n";
  }
  return out.str();
}

} // namespace yawdepth::cli

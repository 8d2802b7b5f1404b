// The API reference in docs/reference/ against the OpenAPI document the
// gateway serves (gateway/rest/openapi.json, built into the binary; the
// rest_tests check that document against the server's routes). Users read
// the reference, so it must list exactly the operations the gateway has,
// with the role each needs, every status it answers and its query
// parameters. And the user documents link only to what is in the repository.
//
// Reference format: one heading per operation, "### `METHOD /path`",
// followed by a line "Role: viewer. Answers: 200, 401, ..." (public
// operations: "Role: none (public).").
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <boost/json.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
namespace json = boost::json;

const fs::path kSource = CANOPEN_SOURCE_DIR;

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  EXPECT_TRUE(in) << "cannot read " << p;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

json::object openapi() {
  boost::system::error_code ec;
  auto v = json::parse(read(kSource / "gateway/rest/openapi.json"), ec);
  EXPECT_FALSE(ec) << "openapi.json: " << ec.message();
  return v.is_object() ? v.as_object() : json::object{};
}

const json::object* deref(const json::object& doc, const json::value& v) {
  const auto* o = v.if_object();
  if (o == nullptr) return nullptr;
  const auto* ref = o->if_contains("$ref");
  if (ref == nullptr) return o;
  std::string_view path = ref->as_string();
  if (!path.starts_with("#/")) return nullptr;
  path.remove_prefix(2);
  const json::object* cur = &doc;
  while (cur != nullptr) {
    const auto slash = path.find('/');
    const auto* next = cur->if_contains(path.substr(0, slash));
    if (next == nullptr) return nullptr;
    if (slash == std::string_view::npos) return next->if_object();
    cur = next->if_object();
    path.remove_prefix(slash + 1);
  }
  return nullptr;
}

struct Operation {
  std::string role;                   // "viewer", ..., or "none (public)"
  std::set<std::string> answers;      // status codes
  std::set<std::string> query;        // query parameter names
};

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// "GET /api/v1/gateway" -> what the OpenAPI document says about it.
std::map<std::string, Operation> described() {
  const auto doc = openapi();
  std::map<std::string, Operation> out;
  for (const auto& [path, item] : doc.at("paths").as_object()) {
    for (const auto& [method, opv] : item.as_object()) {
      if (method == "parameters") continue;
      const auto& op = opv.as_object();
      Operation o;
      const auto* security = op.if_contains("security");
      const bool is_public = security != nullptr && security->as_array().empty();
      o.role = is_public ? "none (public)" : std::string(op.at("x-required-role").as_string());
      for (const auto& [code, r] : op.at("responses").as_object()) o.answers.insert(std::string(code));
      if (const auto* ps = op.if_contains("parameters")) {
        for (const auto& pv : ps->as_array()) {
          const auto* p = deref(doc, pv);
          if (p != nullptr && p->at("in").as_string() == "query") o.query.insert(std::string(p->at("name").as_string()));
        }
      }
      out[upper(std::string(method)) + " " + std::string(path)] = std::move(o);
    }
  }
  return out;
}

std::vector<fs::path> reference_pages() {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(kSource / "docs/reference"))
    if (e.path().extension() == ".md") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

struct Section {
  std::string page;
  std::string text;  // from the heading to the next heading
};

// Every "### `METHOD /path`" of the reference, with its section.
std::multimap<std::string, Section> documented() {
  static const std::regex heading(R"(^### `([A-Z]+ /[^`]*)`\s*$)");
  std::multimap<std::string, Section> out;
  for (const auto& page : reference_pages()) {
    std::istringstream in(read(page));
    std::string line, current;
    Section section;
    auto flush = [&] {
      if (!current.empty()) out.emplace(current, section);
      current.clear();
    };
    while (std::getline(in, line)) {
      std::smatch m;
      if (std::regex_match(line, m, heading)) {
        flush();
        current = m[1];
        section = Section{page.filename().string(), ""};
      } else if (line.starts_with("#")) {
        flush();
      } else if (!current.empty()) {
        section.text += line + "\n";
      }
    }
    flush();
  }
  return out;
}

std::set<std::string> split_codes(const std::string& list) {
  std::set<std::string> out;
  std::istringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    item.erase(0, item.find_first_not_of(' '));
    item.erase(item.find_last_not_of(" .") + 1);
    if (!item.empty()) out.insert(item);
  }
  return out;
}

TEST(ApiReference, ListsEveryOperationOfTheOpenApiDocumentExactlyOnce) {
  const auto told = described();
  const auto docs = documented();
  ASSERT_GE(told.size(), 14U);
  for (const auto& [op, _] : told) EXPECT_EQ(docs.count(op), 1U) << "docs/reference/ has no (or several) ### `" << op << "`";
  for (const auto& [op, s] : docs)
    EXPECT_TRUE(told.count(op)) << s.page << ": ### `" << op << "` is no operation of the OpenAPI document";
}

TEST(ApiReference, StatesTheRoleAndTheAnswersTheOpenApiDocumentGives) {
  static const std::regex line(R"((?:^|\n)Role: ([a-z]+(?: \(public\))?)\. Answers: ([0-9, ]+)\.)");
  const auto told = described();
  for (const auto& [op, s] : documented()) {
    const auto it = told.find(op);
    if (it == told.end()) continue;  // reported above
    SCOPED_TRACE(s.page + ": " + op);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(s.text, m, line)) << "no \"Role: ... Answers: ...\" line";
    EXPECT_EQ(m[1].str(), it->second.role);
    EXPECT_EQ(split_codes(m[2].str()), it->second.answers);
  }
}

TEST(ApiReference, NamesEveryQueryParameter) {
  const auto told = described();
  for (const auto& [op, s] : documented()) {
    const auto it = told.find(op);
    if (it == told.end()) continue;
    for (const auto& q : it->second.query)
      EXPECT_NE(s.text.find("?" + q + "="), std::string::npos) << s.page << ": " << op << " does not show ?" << q << "=";
  }
}

TEST(ApiReference, ListsEveryDataTypeAndEveryEventKind) {
  const auto doc = openapi();
  const auto& schemas = doc.at("components").at("schemas").as_object();
  const std::string rest = read(kSource / "docs/reference/rest.md");
  for (const auto& t : schemas.at("DataType").at("enum").as_array())
    EXPECT_NE(rest.find("`" + std::string(t.as_string()) + "`"), std::string::npos) << "rest.md lacks type " << t;
  const std::string mqtt = read(kSource / "docs/reference/mqtt.md");
  const std::string ws = read(kSource / "docs/reference/websocket.md");
  const auto& kinds = schemas.at("EventEnvelope").at("properties").at("kind").at("enum").as_array();
  EXPECT_EQ(kinds.size(), 11U);
  for (const auto& k : kinds) {
    const std::string kind(k.as_string());
    // A row of the topic table: "| `canopen/...` | `kind` |".
    EXPECT_NE(mqtt.find("| `" + kind + "` |"), std::string::npos) << "mqtt.md's topic table lacks kind " << kind;
    EXPECT_NE(ws.find("`" + kind + "`"), std::string::npos) << "websocket.md lacks kind " << kind;
  }
}

// ---- the user documents as a whole --------------------------------------------

std::vector<fs::path> user_documents() {
  std::vector<fs::path> out = {kSource / "README.md", kSource / "CONTRIBUTING.md"};
  for (const auto& e : fs::recursive_directory_iterator(kSource / "docs"))
    if (e.path().extension() == ".md") out.push_back(e.path());
  return out;
}

// GitHub's anchor of a heading: lower case, punctuation dropped, spaces to '-'.
std::string anchor(const std::string& heading) {
  std::string out;
  for (char ch : heading) {
    const auto c = static_cast<unsigned char>(ch);
    if (std::isalnum(c) || c == '-' || c == '_') out += static_cast<char>(std::tolower(c));
    else if (c == ' ') out += '-';
    else if (c >= 0x80) out += static_cast<char>(c);
  }
  return out;
}

std::set<std::string> anchors(const fs::path& doc) {
  std::set<std::string> out;
  std::istringstream in(read(doc));
  std::string line;
  bool fenced = false;
  while (std::getline(in, line)) {
    if (line.starts_with("```")) fenced = !fenced;
    if (fenced || !line.starts_with("#")) continue;
    const auto text = line.find_first_not_of('#');
    if (text == std::string::npos || line[text] != ' ') continue;
    out.insert(anchor(line.substr(text + 1)));
  }
  return out;
}

TEST(UserDocuments, NeverPointOutsideTheRepository) {
  auto docs = user_documents();
  docs.push_back(kSource / "gateway/rest/openapi.json");  // served to users as it is
  for (const auto& d : docs) EXPECT_EQ(read(d).find("../shared"), std::string::npos) << d << " names ../shared";
}

TEST(UserDocuments, EveryRelativeLinkAndAnchorResolves) {
  static const std::regex link(R"(\]\(([^)\s]+)\))");
  for (const auto& d : user_documents()) {
    const std::string text = read(d);
    for (std::sregex_iterator it(text.begin(), text.end(), link), end; it != end; ++it) {
      const std::string target = (*it)[1];
      if (target.starts_with("http://") || target.starts_with("https://") || target.starts_with("mailto:")) continue;
      const auto hash = target.find('#');
      const std::string file = target.substr(0, hash);
      const fs::path resolved = file.empty() ? d : (d.parent_path() / file).lexically_normal();
      EXPECT_TRUE(fs::exists(resolved)) << d.lexically_relative(kSource) << ": link " << target << " leads nowhere";
      if (hash != std::string::npos && fs::is_regular_file(resolved) && resolved.extension() == ".md") {
        EXPECT_TRUE(anchors(resolved).count(target.substr(hash + 1)))
            << d.lexically_relative(kSource) << ": link " << target << ": no such heading";
      }
    }
  }
}

}  // namespace

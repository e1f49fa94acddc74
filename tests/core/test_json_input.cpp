// JSON text from users (core/json_input.hpp): bad JSON refused naming its source, with a message
// that stays short whatever the text holds, and values and keys echoed in messages only in part.
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/json_input.hpp"
#include "tests/support/scratch.hpp"

using namespace confpack::core;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

/// The message of the std::invalid_argument that `parseJsonText(text, source)` throws.
std::string refusal(const std::string& text, const std::string& source = "in.json") {
  try {
    (void)parseJsonText(text, source);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  FAIL("accepted: " << text.substr(0, 80));
  return {};
}

}  // namespace

TEST_CASE("parseJsonText refuses bad JSON naming its source, and numbers beyond a double") {
  CHECK(parseJsonText(R"({"a": [1, 2.5]})", "x").at("a").at(1) == 2.5);
  CHECK_THAT(refusal("{\"a\": ", "--backend-options"), Catch::StartsWith("--backend-options: not valid JSON"));
  // Issue 23, failure 8: 1e400 gave nlohmann's out_of_range.406 without the file or the field.
  CHECK_THAT(refusal(R"({"a": 1e400})"), Catch::StartsWith("in.json: a: a number out of the range of a double"));
  CHECK_THAT(refusal(R"({"box": {"width": 4}, "grains": [{"size": 1}, {"position": [0, -1e999, 0]}]})"),
             Catch::StartsWith("in.json: grains[1].position[1]: a number out of the range of a double: "
                               "[json.exception.out_of_range.406] number overflow parsing '-1e999'"));
  CHECK_THAT(refusal("[[1, 2], [3, 4, 5e500]]"), Catch::StartsWith("in.json: [1][2]: a number out of the range"));
  // Found by fuzz_packing: 5e500 under many levels of long keys gave a path of thousands of
  // characters; it is cut like any echoed input.
  std::string deep;
  for (int i = 0; i < 100; ++i) deep += "{\"" + std::string(50, 'q') + "\": ";
  deep += "5e500" + std::string(100, '}');
  const std::string message = refusal(deep);
  CHECK_THAT(message, Catch::StartsWith("in.json: " + std::string(50, 'q') + "." + std::string(50, 'q')));
  CHECK(message.size() < 400);
  CHECK_THAT(refusal(""), Catch::StartsWith("in.json: not valid JSON"));
}

TEST_CASE("a parse error does not echo the rest of the file") {
  // Found by fuzz_packing (issue 23): nlohmann's message quotes the token it last read, here 5,000
  // tabs and the bytes after them; the refusal was over 10,000 characters long.
  const std::string tabs = "{\n" + std::string(5000, '\t') + "\x01grains";
  CHECK(refusal(tabs).size() < 400);
  const std::string unterminated = R"({"format": ")" + std::string(100000, 'x');
  const std::string message = refusal(unterminated);
  CHECK(message.size() < 400);
  CHECK_THAT(message, Catch::StartsWith("in.json: not valid JSON") && Catch::EndsWith("..."));
}

TEST_CASE("readJsonFile names the file and its kind when it is a folder, absent or not JSON") {
  const fs::path dir = confpack::testing::freshDir("json_input_read");
  std::ofstream(dir / "bad.json") << "{";
  std::ofstream(dir / "good.json") << R"({"k": true})";
  CHECK(readJsonFile(dir / "good.json", "sweep file").at("k") == true);
  CHECK_THROWS_WITH(readJsonFile(dir, "sweep file"), Catch::EndsWith("is a folder, not a sweep file"));
  CHECK_THROWS_WITH(readJsonFile(dir / "absent.json", "sweep file"),
                    Catch::Contains("absent.json: cannot open the sweep file"));
  CHECK_THROWS_WITH(readJsonFile(dir / "bad.json", "sweep file"), Catch::Contains("bad.json: not valid JSON"));
  fs::remove_all(dir);
}

TEST_CASE("readJsonFile reads regular files only, of a bounded size, and refuses the rest before reading") {
  // The failure this guards against: /dev/zero and /dev/urandom were read for ever (memory without bound, deaf
  // to SIGTERM) and a FIFO without a writer blocked the open for ever. Each is refused at once.
  const fs::path dir = confpack::testing::freshDir("json_input_kinds");
  REQUIRE(::mkfifo((dir / "fifo").c_str(), 0600) == 0);
  CHECK_THROWS_WITH(readJsonFile(dir / "fifo", "packing file"),
                    (dir / "fifo").string() + ": is a FIFO, not a regular file: give the packing file itself");
  CHECK_THROWS_WITH(readJsonFile("/dev/zero", "packing file"),
                    "/dev/zero: is a character device, not a regular file: give the packing file itself");
  CHECK_THROWS_WITH(readJsonFile("/dev/urandom", "packing file"), Catch::Contains("is a character device"));
  // A sparse file one byte over the bound: refused by its size, none of it read.
  { std::ofstream(dir / "huge.json") << "{"; }
  fs::resize_file(dir / "huge.json", kMaxJsonFileBytes + 1);
  CHECK_THROWS_WITH(readJsonFile(dir / "huge.json", "packing file"),
                    Catch::EndsWith(": 2147483649 bytes, more than the 2147483648 bytes a packing file may have"));
  fs::remove_all(dir);
}

TEST_CASE("jsonExcerpt shows short values whole and cuts long or deeply nested ones") {
  CHECK(jsonExcerpt(json::parse(R"([1, "a", {"k": null}])")) == R"([1,"a",{"k":null}])");
  CHECK(jsonExcerpt(json(std::string(10'000'000, 'k'))).size() == 63);  // 60 + "..."
  // 200,000 levels: dump() would recurse 200,000 deep; the excerpt stops at its budget.
  json deep = json::array();
  for (int i = 0; i < 200000; ++i) deep = json::array({std::move(deep)});
  const std::string cut = jsonExcerpt(deep);
  CHECK(cut == std::string(60, '[') + "...");
  const json wide(std::vector<int>(100000, 7));
  CHECK(jsonExcerpt(wide, 20) == "[7,7,7,7,7,7,7,7,7,7...");
}

TEST_CASE("textExcerpt never cuts a UTF-8 character in two") {
  const std::string accents = "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9";  // four e-acute, two bytes each
  CHECK(textExcerpt(accents, 8) == accents);
  CHECK(textExcerpt(accents, 5) == "\xc3\xa9\xc3\xa9...");  // not 5 bytes: the third would be half
  // A message holding the excerpt can be written into a JSON file (failed.json).
  CHECK_NOTHROW(json(textExcerpt(accents, 3)).dump());
}

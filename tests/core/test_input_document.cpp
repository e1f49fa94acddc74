// The reader of input documents (core/input_document.hpp): each refusal is one full "SOURCE:
// FIELD: WHAT" message, for a document of another kind or version, an unknown or missing key and
// a value of the wrong type; an optional header key may be absent, a required one may not.
#include <catch2/catch.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "core/input_document.hpp"

using namespace confpack::core;
using nlohmann::json;

namespace {

const DocumentHeader kRequired{"confpack-example", 2};
const DocumentHeader kOptional{"confpack-example", 2, HeaderKey::Optional, HeaderKey::Optional};

/// The message of the std::invalid_argument that `read` throws.
std::string refusal(const std::function<void()>& read) {
  try {
    read();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

/// The message of readDocument on `doc`, its keys limited to the header's and "items".
std::string documentRefusal(const json& doc, const DocumentHeader& header = kRequired) {
  return refusal([&] { (void)readDocument(doc, "in.json", header, {"format", "version", "items"}); });
}

const json kGood = {{"format", "confpack-example"}, {"version", 2}, {"items", json::array()}};

json with(const std::function<void(json&)>& edit) {
  json doc = kGood;
  edit(doc);
  return doc;
}

}  // namespace

TEST_CASE("input document: a document of another kind or version is refused by its header") {
  CHECK(documentRefusal(kGood) == "accepted");
  CHECK(documentRefusal(with([](json& d) { d["format"] = "confpack-packing"; })) ==
        "in.json: format: must be \"confpack-example\" (got \"confpack-packing\")");
  CHECK(documentRefusal(with([](json& d) { d["format"] = 7; })) ==
        "in.json: format: must be \"confpack-example\" (got 7)");
  CHECK(documentRefusal(with([](json& d) { d["version"] = 3; })) ==
        "in.json: version: must be 2, the version this build reads (got 3)");
  CHECK(documentRefusal(with([](json& d) { d["version"] = "2"; })) ==
        "in.json: version: must be 2, the version this build reads (got \"2\")");
  CHECK(documentRefusal(with([](json& d) { d.erase("format"); })) ==
        "in.json: format: missing (expected \"confpack-example\")");
  CHECK(documentRefusal(with([](json& d) { d.erase("version"); })) == "in.json: version: missing (expected 2)");
  // Compared as JSON numbers: 2.0 is version 2.
  CHECK(documentRefusal(with([](json& d) { d["version"] = 2.0; })) == "accepted");
  CHECK(documentRefusal(json::array()) == "in.json: document: must be a JSON object (got array)");
  // The header is checked before the keys: a file of another kind is told so, not its keys.
  CHECK(documentRefusal({{"format", "other"}, {"grains", 1}}) ==
        "in.json: format: must be \"confpack-example\" (got \"other\")");
}

TEST_CASE("input document: optional header keys may be absent, and are checked when given") {
  CHECK(documentRefusal({{"items", json::array()}}, kOptional) == "accepted");
  CHECK(documentRefusal(json::object(), kOptional) == "accepted");
  CHECK(documentRefusal(with([](json& d) { d.erase("version"); }), kOptional) == "accepted");
  CHECK(documentRefusal(with([](json& d) { d["format"] = "x"; }), kOptional) ==
        "in.json: format: must be \"confpack-example\" (got \"x\")");
  CHECK(documentRefusal(with([](json& d) { d["version"] = 1; }), kOptional) ==
        "in.json: version: must be 2, the version this build reads (got 1)");
  // Only the format required (the run table): the version may then be absent.
  const DocumentHeader formatOnly{"confpack-example", 2, HeaderKey::Required, HeaderKey::Optional};
  CHECK(documentRefusal(with([](json& d) { d.erase("version"); }), formatOnly) == "accepted");
  CHECK(documentRefusal(with([](json& d) { d.erase("format"); }), formatOnly) ==
        "in.json: format: missing (expected \"confpack-example\")");
}

TEST_CASE("input document: an unknown key is named with the known ones, at its path") {
  CHECK(documentRefusal(with([](json& d) { d["itmes"] = 1; })) ==
        "in.json: itmes: unknown key (known: format, version, items)");
  const json grain = {{"size", 1}, {"sahpe", "sphere"}};
  CHECK(refusal([&] {
          ObjectReader(grain, "in.json", "grains[3]").onlyKeys({"shape", "size"});
        }) == "in.json: grains[3].sahpe: unknown key (known: shape, size)");
  // A long key is echoed only in part.
  const json longKey = {{std::string(100, 'k'), 1}};
  CHECK(refusal([&] { ObjectReader(longKey, "in.json", "box").onlyKeys({"width"}); }) ==
        "in.json: box." + std::string(60, 'k') + "...: unknown key (known: width)");
  CHECK(refusal([] { refuseUnknownKey("in.json", "", "colour", "a, b"); }) ==
        "in.json: colour: unknown key (known: a, b)");
  CHECK(keyList({{"b", 1}, {"a", 2}}) == "a, b");
}

TEST_CASE("input document: a missing key is named, with why it is needed when the reader says") {
  const json grain = {{"size", 1}};
  const ObjectReader r(grain, "in.json", "grains[0]");
  CHECK(refusal([&] { (void)r.at("shape"); }) == "in.json: grains[0].shape: missing");
  CHECK(refusal([&] { (void)r.string("shape"); }) == "in.json: grains[0].shape: missing");
  CHECK(refusal([&] { (void)r.at("shape", "a grain needs its shape"); }) ==
        "in.json: grains[0].shape: missing (a grain needs its shape)");
  const json top = json::object();
  CHECK(refusal([&] { (void)ObjectReader(top, "in.json").array("grains"); }) == "in.json: grains: missing");
}

TEST_CASE("input document: a value of the wrong type is refused with what it must be and what it is") {
  const json j = {{"text", 3},       {"flag", 1},          {"count", 2.5},  {"big", 2000000000}, {"size", "1"},
                  {"none", nullptr}, {"list", {{"a", 1}}}, {"map", {1, 2}}, {"neg", -1.5}};
  const ObjectReader r(j, "in.json", "grains[2]");
  CHECK(refusal([&] { (void)r.string("text"); }) == "in.json: grains[2].text: must be a string (got 3)");
  CHECK(refusal([&] { (void)r.boolean("flag"); }) == "in.json: grains[2].flag: must be true or false (got 1)");
  CHECK(refusal([&] { (void)r.integer("count"); }) == "in.json: grains[2].count: must be an integer (got 2.5)");
  CHECK(refusal([&] { (void)r.integer("big"); }) == "in.json: grains[2].big: out of range (got 2000000000)");
  // 2^64 - 1 is an unsigned JSON integer: read as an int64 it would wrap to -1, the floor's id.
  const json huge = json::parse(R"({"b": 18446744073709551615})");
  CHECK(refusal([&] { (void)ObjectReader(huge, "in.json", "contacts[0]").integer("b"); }) ==
        "in.json: contacts[0].b: out of range (got 18446744073709551615)");
  CHECK(refusal([&] { (void)r.number("size"); }) == "in.json: grains[2].size: must be a finite number (got \"1\")");
  // JSON has no spelling for infinity: written, it comes back as null.
  CHECK(refusal([&] { (void)r.number("none"); }) == "in.json: grains[2].none: must be a finite number (got null)");
  CHECK(refusal([&] { (void)r.number("neg", Range::positive()); }) == "in.json: grains[2].neg: must be > 0 (got -1.5)");
  CHECK(refusal([&] { (void)r.array("list"); }) == "in.json: grains[2].list: must be an array (got object)");
  CHECK(refusal([&] { (void)r.object("map"); }) == "in.json: grains[2].map: must be a JSON object (got array)");
  CHECK(refusal([&] { ObjectReader(j.at("map"), "in.json", "grains[2].map"); }) ==
        "in.json: grains[2].map: must be a JSON object (got array)");
  CHECK(refusal([&] { r.refuse("size", "must be > 0 (got -1)"); }) == "in.json: grains[2].size: must be > 0 (got -1)");
  CHECK(refusal([] { refuseInput("in.json", "runs[4].name", "names two runs"); }) ==
        "in.json: runs[4].name: names two runs");
}

TEST_CASE("input document: values of the right type are read as given") {
  const json j = {{"text", "sphere"}, {"flag", true},   {"count", -3},
                  {"size", 0.5},      {"list", {1, 2}}, {"map", {{"a", 1}}}};
  const ObjectReader r(j, "in.json");
  CHECK(r.string("text") == "sphere");
  CHECK(r.boolean("flag"));
  CHECK(r.integer("count") == -3);
  CHECK(r.number("size") == 0.5);
  CHECK(r.number("size", Range::positive()) == 0.5);
  CHECK(r.array("list").size() == 2);
  CHECK(r.object("map").at("a") == 1);
  CHECK(r.field("size") == "size");
  CHECK(ObjectReader(j, "in.json", "box").field("size") == "box.size");
  CHECK(r.has("text"));
  CHECK_FALSE(r.has("other"));
}

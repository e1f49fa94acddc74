#pragma once
// The study report as a document: a list of blocks (headings, paragraphs, bullet lists, tables,
// figures) that the report's sections append once and that renders to a self-contained HTML page
// (figures inlined as SVG) and to Markdown (figures linked to figures/STEM.svg). Both renderings
// come from the same blocks, so they cannot drift apart. Text may hold links written as in
// Markdown, [text](target) (made by link()): Markdown keeps them, HTML makes them <a href>.
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace confpack::study {

struct Heading {
  int level = 1;
  std::string text;
};

struct Paragraph {
  std::string text;
};

struct BulletList {
  std::vector<std::string> items;
};

struct Table {
  std::vector<std::string> head;
  std::vector<std::vector<std::string>> rows;
};

/// A figure of figures/: its data is figures/STEM.csv and its script figures/STEM.gp. svg is the
/// drawing (empty when not drawn); error says why gnuplot failed on it (empty when it did not).
struct Figure {
  std::string stem;
  std::string caption;
  std::string svg;
  std::string error;
};

/// A link in the text of any block: "[text](target)", the target percent-encoded except for the
/// characters of a relative path (letters, digits, '/', '.', '-', '_', '~').
std::string link(std::string_view text, std::string_view target);

using Block = std::variant<Heading, Paragraph, BulletList, Table, Figure>;

class Document {
 public:
  explicit Document(std::string title = {}) : title_(std::move(title)) {}

  void heading(int level, std::string text) { blocks_.emplace_back(Heading{level, std::move(text)}); }
  void paragraph(std::string text) { blocks_.emplace_back(Paragraph{std::move(text)}); }
  void bullets(std::vector<std::string> items) { blocks_.emplace_back(BulletList{std::move(items)}); }
  /// A table without rows is written as the paragraph "(no data)".
  void table(std::vector<std::string> head, std::vector<std::vector<std::string>> rows);
  void figure(Figure f) { blocks_.emplace_back(std::move(f)); }

  const std::string& title() const { return title_; }
  const std::vector<Block>& blocks() const { return blocks_; }

 private:
  std::string title_;
  std::vector<Block> blocks_;
};

/// Markdown: cells escape '|'; other text is written as is.
std::string renderMarkdown(const Document& doc);

/// One HTML page with its style sheet; text is escaped, links made anchors, SVG inlined, and a
/// cell that reports a problem (missing, failed, pending, incomplete, NOT equilibrated, a
/// significant difference (*)) is highlighted.
std::string renderHtml(const Document& doc);

}  // namespace confpack::study

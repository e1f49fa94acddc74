#include "study/report_document.hpp"

#include <fmt/format.h>

#include <cctype>
#include <sstream>

namespace confpack::study {

namespace {

std::string htmlEscape(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Escaped text with its links "[text](target)" made anchors; a '[' that opens no link is text.
std::string htmlText(std::string_view s) {
  constexpr auto npos = std::string_view::npos;
  std::string out;
  std::size_t at = 0;
  while (at < s.size()) {
    const std::size_t open = s.find('[', at);
    if (open == npos) break;
    const std::size_t close = s.find("](", open);
    const std::size_t end = close == npos ? npos : s.find(')', close);
    const std::string_view text = end == npos ? "" : s.substr(open + 1, close - open - 1);
    const std::string_view target = end == npos ? "" : s.substr(close + 2, end - close - 2);
    if (end == npos || text.find('[') != npos || target.empty() || target.find_first_of(" []") != npos) {
      out += htmlEscape(s.substr(at, open + 1 - at));
      at = open + 1;
      continue;
    }
    out += htmlEscape(s.substr(at, open - at));
    out += fmt::format("<a href=\"{}\">{}</a>", htmlEscape(target), htmlEscape(text));
    at = end + 1;
  }
  if (at < s.size()) out += htmlEscape(s.substr(at));
  return out;
}

std::string mdEscape(std::string_view s) {
  std::string out;
  for (char c : s) {
    if (c == '|')
      out += "\\|";
    else
      out += c;
  }
  return out;
}

bool flagged(const std::string& c) {
  return c == "missing" || c.find("FAILED") != std::string::npos || c.find("(*)") != std::string::npos ||
         c.find("NOT") != std::string::npos || c == "failed" || c == "pending" || c == "incomplete";
}

// Why a figure has no drawing, after "not drawn".
std::string notDrawnReason(const Figure& f) {
  return f.error.empty() ? "" : ": " + f.error;
}

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

void markdownBlock(std::ostream& md, const Block& block) {
  std::visit(Overloaded{
                 [&](const Heading& h) {
                   md << std::string(static_cast<std::size_t>(h.level), '#') << ' ' << h.text << "\n\n";
                 },
                 [&](const Paragraph& p) { md << p.text << "\n\n"; },
                 [&](const BulletList& l) {
                   for (const auto& i : l.items) md << "- " << i << "\n";
                   md << "\n";
                 },
                 [&](const Table& t) {
                   md << '|';
                   for (const auto& h : t.head) md << ' ' << mdEscape(h) << " |";
                   md << "\n|";
                   for (std::size_t i = 0; i < t.head.size(); ++i) md << "---|";
                   md << '\n';
                   for (const auto& row : t.rows) {
                     md << '|';
                     for (const auto& c : row) md << ' ' << mdEscape(c) << " |";
                     md << "\n";
                   }
                   md << "\n";
                 },
                 [&](const Figure& f) {
                   if (f.svg.empty())
                     md << fmt::format(
                         "*Figure {}: {}* (not drawn{}; data in [figures/{}.csv](figures/{}.csv), "
                         "script figures/{}.gp)\n\n",
                         f.stem, f.caption, notDrawnReason(f), f.stem, f.stem, f.stem);
                   else
                     md << fmt::format("![{}](figures/{}.svg)\n\n*{}* (data: [figures/{}.csv](figures/{}.csv))\n\n",
                                       f.caption, f.stem, f.caption, f.stem, f.stem);
                 },
             },
             block);
}

void htmlBlock(std::ostream& html, const Block& block) {
  std::visit(Overloaded{
                 [&](const Heading& h) { html << fmt::format("<h{0}>{1}</h{0}>\n", h.level, htmlEscape(h.text)); },
                 [&](const Paragraph& p) { html << "<p>" << htmlText(p.text) << "</p>\n"; },
                 [&](const BulletList& l) {
                   html << "<ul>\n";
                   for (const auto& i : l.items) html << "<li>" << htmlText(i) << "</li>\n";
                   html << "</ul>\n";
                 },
                 [&](const Table& t) {
                   html << "<table>\n<tr>";
                   for (const auto& h : t.head) html << "<th>" << htmlEscape(h) << "</th>";
                   html << "</tr>\n";
                   for (const auto& row : t.rows) {
                     html << "<tr>";
                     for (const auto& c : row)
                       html << (flagged(c) ? "<td class=\"flag\">" : "<td>") << htmlText(c) << "</td>";
                     html << "</tr>\n";
                   }
                   html << "</table>\n";
                 },
                 [&](const Figure& f) {
                   if (f.svg.empty())
                     html << fmt::format(
                         "<p class=\"fig\"><em>Figure {}: {}</em> (not drawn{}; data in figures/{}.csv)</p>\n", f.stem,
                         htmlEscape(f.caption), htmlEscape(notDrawnReason(f)), f.stem);
                   else
                     html << "<figure>" << f.svg << "<figcaption>" << htmlEscape(f.caption) << " (data: figures/"
                          << f.stem << ".csv)</figcaption></figure>\n";
                 },
             },
             block);
}

}  // namespace

std::string link(std::string_view text, std::string_view target) {
  std::string encoded;
  for (const char c : target) {
    const auto u = static_cast<unsigned char>(c);
    if (std::isalnum(u) || c == '/' || c == '.' || c == '-' || c == '_' || c == '~')
      encoded += c;
    else
      encoded += fmt::format("%{:02X}", u);
  }
  return fmt::format("[{}]({})", text, encoded);
}

void Document::table(std::vector<std::string> head, std::vector<std::vector<std::string>> rows) {
  if (rows.empty()) {
    paragraph("(no data)");
    return;
  }
  blocks_.emplace_back(Table{std::move(head), std::move(rows)});
}

std::string renderMarkdown(const Document& doc) {
  std::ostringstream md;
  for (const Block& b : doc.blocks()) markdownBlock(md, b);
  return md.str();
}

std::string renderHtml(const Document& doc) {
  std::ostringstream body;
  for (const Block& b : doc.blocks()) htmlBlock(body, b);
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\n"
      "body{{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}}\n"
      "table{{border-collapse:collapse;margin:0.5em 0 1.5em;font-size:90%}}\n"
      "th,td{{border:1px solid #bbb;padding:2px 6px;text-align:right}} th{{background:#eee}}\n"
      "td.flag{{background:#fde2e2}} figure{{margin:1em 0}} figure svg{{max-width:100%;height:auto}}\n"
      "figcaption{{font-size:90%;color:#444}}\n</style></head><body>\n{}</body></html>\n",
      htmlEscape(doc.title()), body.str());
}

}  // namespace confpack::study

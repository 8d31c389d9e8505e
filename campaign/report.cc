#include "jointlab/campaign/report.h"

#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/atomic_file.h"

namespace jointlab::campaign {

namespace {

namespace fs = std::filesystem;

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot read the figure", p.string()));
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void check_table(const ReportTable& t) {
  for (const auto& row : t.rows)
    if (row.size() != t.header.size())
      throw InputError(fmt::format("report table '{}': a row of {} cells under {} columns",
                                   t.caption, row.size(), t.header.size()));
}

// Markdown cells: '|' would end the cell.
std::string md_cell(std::string s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

}  // namespace

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += table[(v >> 6) & 63];
    out += table[v & 63];
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8);
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += table[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

std::string html_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
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

void write_report_html(const Report& r, const fs::path& path) {
  std::string h = fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n"
      "<style>\nbody {{ font-family: sans-serif; max-width: 60em; margin: 2em auto; "
      "color: #111; }}\ntable {{ border-collapse: collapse; margin: 0.5em 0 1.5em; }}\n"
      "th, td {{ border: 1px solid #bbb; padding: 0.2em 0.6em; text-align: right; }}\n"
      "th {{ background: #eee; }}\nfigure {{ margin: 1em 0; }}\nimg {{ max-width: 100%; }}\n"
      "figcaption {{ font-size: 0.9em; color: #444; }}\n</style>\n</head>\n<body>\n<h1>{}</h1>\n",
      html_escape(r.title), html_escape(r.title));
  for (const ReportSection& s : r.sections) {
    h += fmt::format("<h2>{}</h2>\n", html_escape(s.heading));
    for (const std::string& p : s.paragraphs) h += fmt::format("<p>{}</p>\n", html_escape(p));
    for (const ReportTable& t : s.tables) {
      check_table(t);
      if (!t.caption.empty()) h += fmt::format("<p><b>{}</b></p>\n", html_escape(t.caption));
      h += "<table>\n<tr>";
      for (const std::string& c : t.header) h += fmt::format("<th>{}</th>", html_escape(c));
      h += "</tr>\n";
      for (const auto& row : t.rows) {
        h += "<tr>";
        for (const std::string& c : row) h += fmt::format("<td>{}</td>", html_escape(c));
        h += "</tr>\n";
      }
      h += "</table>\n";
    }
    for (const ReportFigure& f : s.figures) {
      h += fmt::format(
          "<figure><img alt=\"{}\" src=\"data:image/png;base64,{}\"><figcaption>{}</figcaption>"
          "</figure>\n",
          html_escape(f.caption), base64(read_bytes(f.image)), html_escape(f.caption));
    }
  }
  h += "</body>\n</html>\n";
  data::write_file_atomically(path, h);
}

void write_report_markdown(const Report& r, const fs::path& path) {
  const fs::path dir = fs::absolute(path).parent_path();
  std::string m = fmt::format("# {}\n", r.title);
  for (const ReportSection& s : r.sections) {
    m += fmt::format("\n## {}\n", s.heading);
    for (const std::string& p : s.paragraphs) m += fmt::format("\n{}\n", p);
    for (const ReportTable& t : s.tables) {
      check_table(t);
      if (!t.caption.empty()) m += fmt::format("\n**{}**\n", t.caption);
      m += "\n|";
      for (const std::string& c : t.header) m += fmt::format(" {} |", md_cell(c));
      m += "\n|";
      for (size_t i = 0; i < t.header.size(); ++i) m += "---|";
      m += "\n";
      for (const auto& row : t.rows) {
        m += "|";
        for (const std::string& c : row) m += fmt::format(" {} |", md_cell(c));
        m += "\n";
      }
    }
    for (const ReportFigure& f : s.figures) {
      const fs::path rel = fs::absolute(f.image).lexically_relative(dir);
      m += fmt::format("\n![{}]({})\n\n*{}*\n", f.caption, rel.generic_string(), f.caption);
    }
  }
  data::write_file_atomically(path, m);
}

}  // namespace jointlab::campaign

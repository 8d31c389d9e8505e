// A campaign report: one self-contained HTML file (figures embedded as base64 PNG data
// URIs, no external file) and its Markdown twin (figures linked by relative path).
//
// A report is a title and sections; a section holds paragraphs, tables and figures in
// that order. Text is plain (HTML special characters are escaped); tables are strings.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace jointlab::campaign {

/// A table of text cells.
struct ReportTable {
  std::string caption;                         ///< line above the table
  std::vector<std::string> header;             ///< column names
  std::vector<std::vector<std::string>> rows;  ///< cells, each row as long as the header
};

/// A PNG figure.
struct ReportFigure {
  std::string caption;          ///< line below the figure
  std::filesystem::path image;  ///< the PNG file
};

/// One section.
struct ReportSection {
  std::string heading;                  ///< section title
  std::vector<std::string> paragraphs;  ///< plain text paragraphs
  std::vector<ReportTable> tables;      ///< after the paragraphs
  std::vector<ReportFigure> figures;    ///< after the tables
};

/// The whole report.
struct Report {
  std::string title;                    ///< page title
  std::vector<ReportSection> sections;  ///< in order
};

/// Standard base64 (RFC 4648, with '=' padding) of a byte string.
std::string base64(const std::string& bytes);

/// Escapes &, <, > and " for HTML text.
std::string html_escape(const std::string& text);

/// Writes the report as one self-contained HTML file, atomically; InputError when a
/// figure cannot be read or a table row has the wrong length.
void write_report_html(const Report& report, const std::filesystem::path& path);

/// Writes the report as Markdown, atomically; figures are linked relative to the file.
void write_report_markdown(const Report& report, const std::filesystem::path& path);

}  // namespace jointlab::campaign

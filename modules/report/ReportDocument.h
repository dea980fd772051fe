#pragma once
/// @file ReportDocument.h
/// @brief A printed document built from headings, paragraphs, tables and
/// figures, laid out by Qt's rich-text engine onto pages of a PDF file or a
/// printer, with the patient line and the page number on every page
/// (thesis §2.1: a plan is documented for the team, the patient and the record).

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <QImage>

class QPagedPaintDevice;

namespace caps::report {

enum class PaperSize
{
  A4,
  Letter
};

/// @a value with @a decimals digits after the point, as the reports print
/// numbers; @a missing for NaN or infinity (a measure with no value).
std::string fixed(double value, int decimals, const std::string& missing = "n/a");

/// What a PDF file says about itself (its document information).
struct PdfMetadata
{
  std::string title;
  std::string creator; ///< "CAPS 0.1.0"
};

class ReportDocument
{
public:
  /// @a title is printed at the top right of every page.
  explicit ReportDocument(std::string title);

  /// The line at the top left of every page: who the plan is for.
  void setPatientLine(std::string line) { patientLine_ = std::move(line); }
  /// A note at the bottom left of every page, beside the page number.
  void setFooterNote(std::string note) { footerNote_ = std::move(note); }

  /// @name Content, in reading order (text is plain, not markup)
  ///@{
  void heading(const std::string& text, int level = 1);
  void paragraph(const std::string& text);
  /// A two-column table of names and values.
  void fields(const std::vector<std::pair<std::string, std::string>>& rows);
  /// A table with a header row; numbers are right-aligned. @a widthPercent,
  /// when given (one per column), sets each column's share of the page's
  /// width, so that words such as "approximate" are not broken in a column
  /// the layout would make too narrow.
  void table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
             const std::vector<int>& widthPercent = {});
  /// Figures side by side, each @a widthMm wide on paper, and their
  /// captions under them, lettered (a), (b), ... when there are several
  /// (unless @a lettered is false: captions numbered by the caller).
  void figures(const std::vector<QImage>& images, double widthMm, const std::vector<std::string>& captions,
               bool lettered = true);
  /// The next content starts on a new page.
  void pageBreak();
  ///@}

  /// Lays the document out on @a device (a QPdfWriter, a QPrinter), page
  /// after page; returns the number of pages. The device's page size and
  /// margins are used as they are set.
  /// @throws std::runtime_error when a painter cannot be opened on it.
  int render(QPagedPaintDevice& device) const;

  /// Writes a PDF at 300 dpi on @a paper with 15 mm margins, atomically
  /// (beside, then renamed: an old report is not lost to a failure).
  /// Returns the number of pages.
  /// @throws std::runtime_error when the file cannot be written.
  int writePdf(const std::filesystem::path& file, PaperSize paper, const PdfMetadata& metadata) const;

  /// The document as HTML (for tests and for debugging the layout).
  const std::string& html() const { return html_; }

private:
  /// The style that starts the next block on a new page, once, after pageBreak().
  std::string breakStyle();

  bool pageBreakPending_ = false;
  std::string title_;
  std::string patientLine_;
  std::string footerNote_;
  std::string html_;
  struct Figure
  {
    std::string name;
    QImage image;
    double widthMm;
  };
  std::vector<Figure> images_;
};

/// Escapes text for HTML.
std::string escapeHtml(const std::string& text);

} // namespace caps::report

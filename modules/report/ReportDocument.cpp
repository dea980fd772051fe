#include "modules/report/ReportDocument.h"

#include <sstream>
#include <cmath>
#include <stdexcept>

#include <QAbstractTextDocumentLayout>
#include <QFile>
#include <QFont>
#include <QPageLayout>
#include <QPageSize>
#include <QPagedPaintDevice>
#include <QPainter>
#include <QPdfWriter>
#include <QTextBlock>
#include <QTextLayout>
#include <QTextDocument>
#include <QUrl>

#include "render/GuiForPainting.h"

namespace caps::report {
namespace {

constexpr double kMmPerInch = 25.4;

bool looksNumeric(const std::string& text)
{
  if (text.empty())
    return false;
  std::size_t digits = 0;
  for (char c : text)
  {
    if (c >= '0' && c <= '9')
      ++digits;
    else if (c != '.' && c != '-' && c != '+' && c != ' ' && c != 'e' && c != '%' && c != ',')
      return false;
  }
  return digits > 0;
}

/// The first heading left alone at the foot of a page, its text on the next
/// one: its index among the document's headings, or -1. Qt's rich text keeps
/// lines together but not a heading with what follows it.
int orphanHeading(const QTextDocument& document, double pageHeight)
{
  QAbstractTextDocumentLayout* layout = document.documentLayout();
  const auto pageOf = [&](double y) { return int(std::floor(y / pageHeight)); };
  int index = -1;
  for (QTextBlock block = document.begin(); block.isValid(); block = block.next())
  {
    if (block.blockFormat().headingLevel() == 0)
      continue;
    ++index;
    const QTextBlock next = block.next();
    if (!next.isValid())
      continue;
    // A block that does not fit keeps its top on this page and moves its
    // first line down to the next: compare where that line is.
    double nextTop = layout->blockBoundingRect(next).top();
    if (next.layout() && next.layout()->lineCount() > 0)
      nextTop += next.layout()->lineAt(0).y();
    if (pageOf(layout->blockBoundingRect(block).top()) < pageOf(nextTop + 1.0))
      return index;
  }
  return -1;
}

/// @a html with the @a index-th heading (<h1> to <h3>) starting a new page.
std::string breakBeforeHeading(std::string html, int index)
{
  std::size_t at = 0;
  for (int seen = -1; (at = html.find("<h", at)) != std::string::npos; at += 2)
    if (at + 2 < html.size() && html[at + 2] >= '1' && html[at + 2] <= '3' && ++seen == index)
    {
      if (html.compare(at + 3, 7, " style=") != 0)
        html.insert(at + 3, " style=\"page-break-before: always\"");
      break;
    }
  return html;
}

/// The token a figure's width is written as until the device's resolution is known.
std::string widthToken(std::size_t figure)
{
  return "@@W" + std::to_string(figure) + "@@";
}

} // namespace

std::string escapeHtml(const std::string& text)
{
  std::string out;
  out.reserve(text.size());
  for (char c : text)
    switch (c)
    {
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
    case '\n':
      out += "<br/>";
      break;
    default:
      out += c;
    }
  return out;
}

ReportDocument::ReportDocument(std::string title) : title_(std::move(title)) {}

std::string ReportDocument::breakStyle()
{
  const bool pending = pageBreakPending_;
  pageBreakPending_ = false;
  return pending ? " style=\"page-break-before: always\"" : "";
}

void ReportDocument::heading(const std::string& text, int level)
{
  const std::string h = std::to_string(std::clamp(level, 1, 3));
  html_ += "<h" + h + breakStyle() + ">" + escapeHtml(text) + "</h" + h + ">\n";
}

void ReportDocument::paragraph(const std::string& text)
{
  html_ += "<p" + breakStyle() + ">" + escapeHtml(text) + "</p>\n";
}

void ReportDocument::fields(const std::vector<std::pair<std::string, std::string>>& rows)
{
  html_ += "<table" + breakStyle() + " cellspacing=\"0\" cellpadding=\"2\">\n";
  for (const auto& [name, value] : rows)
    html_ += "<tr><td width=\"38%\"><b>" + escapeHtml(name) + "</b></td><td>" + escapeHtml(value) + "</td></tr>\n";
  html_ += "</table>\n";
}

void ReportDocument::table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                           const std::vector<int>& widthPercent)
{
  if (!widthPercent.empty() && widthPercent.size() != header.size())
    throw std::invalid_argument("ReportDocument::table: one width per column");
  html_ += "<table" + breakStyle() + " border=\"1\" cellspacing=\"0\" cellpadding=\"3\" width=\"100%\">\n<tr>";
  for (std::size_t c = 0; c < header.size(); ++c)
  {
    html_ += "<th bgcolor=\"#e8ecf2\"";
    if (!widthPercent.empty())
      html_ += " width=\"" + std::to_string(widthPercent[c]) + "%\"";
    html_ += '>';
    html_ += escapeHtml(header[c]);
    html_ += "</th>";
  }
  html_ += "</tr>\n";
  for (const auto& row : rows)
  {
    html_ += "<tr>";
    for (const auto& cell : row)
      html_ += std::string(looksNumeric(cell) ? "<td align=\"right\">" : "<td>") + escapeHtml(cell) + "</td>";
    html_ += "</tr>\n";
  }
  html_ += "</table>\n";
}

void ReportDocument::figures(const std::vector<QImage>& images, double widthMm,
                             const std::vector<std::string>& captions, bool lettered)
{
  // One paragraph of images: a line of the layout, which moves whole to the
  // next page when it does not fit (a table cell would be cut in two).
  html_ += "<p align=\"center\"" + breakStyle() + ">";
  for (std::size_t i = 0; i < images.size(); ++i)
  {
    const std::size_t index = images_.size();
    images_.push_back({"figure" + std::to_string(index), images[i], widthMm});
    html_ += std::string(i == 0 ? "" : "&nbsp;&nbsp;") + "<img src=\"" + images_.back().name + "\" width=\"" +
             widthToken(index) + "\"/>";
  }
  html_ += "</p>\n";
  std::string caption;
  for (std::size_t i = 0; i < captions.size(); ++i)
  {
    if (captions[i].empty())
      continue;
    if (!caption.empty())
      caption += " ";
    if (lettered && captions.size() > 1)
    {
      caption += '(';
      caption += char('a' + i);
      caption += ") ";
    }
    caption += escapeHtml(captions[i]);
  }
  if (!caption.empty())
    html_ += "<p align=\"center\" class=\"caption\">" + caption + "</p>\n";
}

void ReportDocument::pageBreak()
{
  pageBreakPending_ = !html_.empty();
}

int ReportDocument::render(QPagedPaintDevice& device) const
{
  render::GuiForPainting gui;
  const double dpi = device.logicalDpiX();
  const double mm = dpi / kMmPerInch; // device pixels per millimetre
  const double width = device.width(), height = device.height();
  const double headerHeight = 10.0 * mm, footerHeight = 8.0 * mm;
  const QSizeF body(width, height - headerHeight - footerHeight);

  QTextDocument document;
  document.documentLayout()->setPaintDevice(&device);
  QFont font("DejaVu Sans");
  font.setPointSizeF(9.5);
  // No ligatures: "fi" stays two letters, so the PDF's text can be searched and copied.
  font.setStyleStrategy(QFont::PreferNoShaping);
  document.setDefaultFont(font);
  document.setDocumentMargin(0);
  document.setPageSize(body);
  document.setDefaultStyleSheet("h1 { font-size: 15pt; color: #1d3557; margin-top: 6px; }"
                                "h2 { font-size: 12pt; color: #1d3557; margin-top: 8px; }"
                                "h3 { font-size: 10.5pt; color: #1d3557; }"
                                "th { font-weight: bold; }"
                                ".caption { font-size: 8pt; color: #333333; }");
  std::string html = html_;
  for (std::size_t i = 0; i < images_.size(); ++i)
  {
    document.addResource(QTextDocument::ImageResource, QUrl(QString::fromStdString(images_[i].name)), images_[i].image);
    const std::string token = widthToken(i);
    // Qt's rich text scales HTML image sizes from 96 dpi to the device's resolution.
    const std::string pixels = std::to_string(int(std::lround(images_[i].widthMm / kMmPerInch * 96.0)));
    for (std::size_t at = html.find(token); at != std::string::npos; at = html.find(token, at))
      html.replace(at, token.size(), pixels);
  }
  document.setHtml(QString::fromStdString(html));
  // Headings are moved from the top down, laying out again after each: a move
  // pushes what follows down and may mend or make a later orphan.
  for (int moves = 0, heading; moves < 20 && (heading = orphanHeading(document, body.height())) >= 0; ++moves)
  {
    html = breakBeforeHeading(html, heading);
    document.setHtml(QString::fromStdString(html));
  }
  const int pages = std::max(1, document.pageCount());

  QPainter painter;
  if (!painter.begin(&device))
    throw std::runtime_error("cannot draw on the report's page device (the file or the printer refused)");
  QFont small = font;
  small.setPointSizeF(7.5);
  for (int page = 0; page < pages; ++page)
  {
    if (page > 0)
      device.newPage();
    // Header: patient line left, title right, a rule under them.
    painter.setFont(small);
    painter.setPen(QColor(40, 40, 40));
    const QRectF headerText(0, 0, width, headerHeight - 2.5 * mm);
    painter.drawText(headerText, Qt::AlignLeft | Qt::AlignBottom, QString::fromStdString(patientLine_));
    painter.drawText(headerText, Qt::AlignRight | Qt::AlignBottom, QString::fromStdString(title_));
    painter.setPen(QPen(QColor(29, 53, 87), 0.3 * mm));
    painter.drawLine(QPointF(0, headerHeight - 1.5 * mm), QPointF(width, headerHeight - 1.5 * mm));
    // Footer: note left, page number right.
    painter.setPen(QColor(40, 40, 40));
    const QRectF footerText(0, height - footerHeight + 2.0 * mm, width, footerHeight - 2.0 * mm);
    painter.drawText(footerText, Qt::AlignLeft | Qt::AlignTop, QString::fromStdString(footerNote_));
    painter.drawText(footerText, Qt::AlignRight | Qt::AlignTop, QString("Page %1 of %2").arg(page + 1).arg(pages));
    // The page's slice of the laid-out body.
    painter.save();
    painter.translate(0, headerHeight - page * body.height());
    document.drawContents(&painter, QRectF(0, page * body.height(), body.width(), body.height()));
    painter.restore();
  }
  painter.end();
  return pages;
}

int ReportDocument::writePdf(const std::filesystem::path& file, PaperSize paper, const PdfMetadata& metadata) const
{
  const std::filesystem::path beside = file.string() + ".writing";
  int pages = 0;
  {
    render::GuiForPainting gui; // QPdfWriter's fonts
    QPdfWriter writer(QString::fromStdString(beside.string()));
    writer.setResolution(300);
    writer.setPageSize(QPageSize(paper == PaperSize::A4 ? QPageSize::A4 : QPageSize::Letter));
    writer.setPageMargins(QMarginsF(15, 12, 15, 12), QPageLayout::Millimeter);
    writer.setTitle(QString::fromStdString(metadata.title));
    writer.setCreator(QString::fromStdString(metadata.creator));
    pages = render(writer);
  }
  std::error_code error;
  std::filesystem::rename(beside, file, error);
  if (error)
  {
    std::filesystem::remove(beside, error);
    throw std::runtime_error("cannot write the report " + file.string() + ": " + error.message());
  }
  return pages;
}

std::string fixed(double value, int decimals, const std::string& missing)
{
  if (!std::isfinite(value))
    return missing;
  std::ostringstream s;
  s.precision(decimals);
  s << std::fixed << value;
  return s.str();
}

} // namespace caps::report

#include "mvod/plot.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <new>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "util/errbuf.h"
#include "util/image_file.h"
#include "util/shim_guard.hpp"

namespace {

const int CANVAS_W = MVOD_PLOT_WIDTH, CANVAS_H = MVOD_PLOT_HEIGHT;
/* Left: z tick labels and the rotated axis label; bottom: x tick labels and axis label. */
const cv::Rect PLOT_RECT(90, 60, CANVAS_W - 90 - 30, CANVAS_H - 60 - 80);
/* Room inside the frame for markers and the heading arrow. */
const double PAD_PX = 45.0;
/* A static camera still gets a readable metre-scale grid. */
const double MIN_EXTENT_M = 1.0;
const double MAX_COORD_M = 1e9;
const double TICK_TARGET_PX = 90.0;
const double ARROW_PX = 40.0;
const int FONT = cv::FONT_HERSHEY_SIMPLEX;
/* Drawing in 1/16 px (cv shift 4) keeps anti-aliased curves smooth. */
const int SHIFT = 4;
const double SUBPIX = 16.0;

const cv::Scalar WHITE(255, 255, 255), BLACK(0, 0, 0), GRID(225, 225, 225);
const cv::Scalar EST_COLOR(190, 90, 20), GT_COLOR(70, 70, 70), START_COLOR(40, 160, 40),
	HEADING_COLOR(30, 30, 210), NEUTRAL(110, 110, 110);

/*
 * Data (x, z) to pixels of a w x h plot area centred on (cx, cz): x right, z up. The top-down
 * view has sx = sz (metres on both axes); a chart scales each axis to its data.
 */
struct View {
	double cx, cz, sx, sz;
	int w, h;
	cv::Point2d px(double x, double z) const
	{
		return {w / 2.0 + (x - cx) * sx, h / 2.0 - (z - cz) * sz};
	}
	double x_at(double u) const { return cx + (u - w / 2.0) / sx; }
	double z_at(double v) const { return cz - (v - h / 2.0) / sz; }
};

struct Path {
	const double *xyz;
	int n;
};

/*
 * A pose with a non-finite coordinate, or one a million kilometres out, is a diverged estimate,
 * not a place: it is left out, which also keeps the view arithmetic far from overflow.
 */
bool valid_at(const Path &p, int i)
{
	const double *q = p.xyz + 3 * i;
	return std::fabs(q[0]) <= MAX_COORD_M && std::fabs(q[1]) <= MAX_COORD_M &&
	       std::fabs(q[2]) <= MAX_COORD_M;
}

cv::Point fixed(cv::Point2d p)
{
	return {(int)std::lround(p.x * SUBPIX), (int)std::lround(p.y * SUBPIX)};
}

/* Pixel positions of the valid points of a path. */
std::vector<cv::Point2d> project(const View &v, const Path &p)
{
	std::vector<cv::Point2d> pts;
	for (int i = 0; i < p.n; i++)
		if (valid_at(p, i))
			pts.push_back(v.px(p.xyz[3 * i], p.xyz[3 * i + 2]));
	return pts;
}

void grow_box(const Path &p, cv::Point2d &lo, cv::Point2d &hi)
{
	for (int i = 0; i < p.n; i++) {
		if (!valid_at(p, i))
			continue;
		lo.x = std::min(lo.x, p.xyz[3 * i]);
		hi.x = std::max(hi.x, p.xyz[3 * i]);
		lo.y = std::min(lo.y, p.xyz[3 * i + 2]);
		hi.y = std::max(hi.y, p.xyz[3 * i + 2]);
	}
}

View fit_view(const Path &est, const Path &gt)
{
	cv::Point2d lo(HUGE_VAL, HUGE_VAL), hi(-HUGE_VAL, -HUGE_VAL);
	grow_box(est, lo, hi);
	grow_box(gt, lo, hi);
	if (lo.x > hi.x)
		lo = hi = cv::Point2d(0, 0);
	double span_x = std::max(hi.x - lo.x, MIN_EXTENT_M);
	double span_z = std::max(hi.y - lo.y, MIN_EXTENT_M);
	double scale = std::min((PLOT_RECT.width - 2 * PAD_PX) / span_x,
				(PLOT_RECT.height - 2 * PAD_PX) / span_z);
	return {(lo.x + hi.x) / 2, (lo.y + hi.y) / 2, scale, scale, PLOT_RECT.width,
		PLOT_RECT.height};
}

double nice_step(double raw)
{
	return mvod_plot_nice_step(raw);
}

std::string tick_label(double value, double step)
{
	char buf[32];
	mvod_plot_tick_label(value, step, buf, sizeof(buf));
	return buf;
}

void put_text(cv::Mat &img, const std::string &s, cv::Point org, double size, int thick = 1,
	      const cv::Scalar &color = BLACK)
{
	cv::putText(img, s, org, FONT, size, color, thick, cv::LINE_AA);
}

cv::Size text_size(const std::string &s, double size, int thick = 1)
{
	int baseline;
	return cv::getTextSize(s, FONT, size, thick, &baseline);
}

/* A grid line at plot column u and its label under the plot; rect: the plot on the canvas. */
void x_tick(cv::Mat &canvas, cv::Mat &plot, const cv::Rect &rect, int u, const std::string &s)
{
	cv::line(plot, {u, 0}, {u, rect.height}, GRID, 1);
	cv::Size ts = text_size(s, 0.5);
	put_text(canvas, s, {rect.x + u - ts.width / 2, rect.br().y + 22}, 0.5);
}

void draw_x_ticks(cv::Mat &canvas, cv::Mat &plot, const cv::Rect &rect, const View &v,
		  double step)
{
	for (long k = std::lround(std::ceil(v.x_at(0) / step)); k * step <= v.x_at(rect.width);
	     k++)
		x_tick(canvas, plot, rect, (int)std::lround(v.px(k * step, 0).x),
		       tick_label(k * step, step));
}

/* The values 1, 2 and 5 (or every 1..9) times powers of ten within [lo, hi] of log10 x. */
std::vector<double> log_ticks(double lo, double hi, bool every_digit)
{
	std::vector<double> ticks;
	for (int k = (int)std::floor(lo); k <= (int)std::ceil(hi); k++)
		for (int m = 1; m <= 9; m++) {
			double lx = std::log10((double)m) + k;
			if ((every_digit || m == 1 || m == 2 || m == 5) && lx >= lo && lx <= hi)
				ticks.push_back(m * std::pow(10.0, k));
		}
	return ticks;
}

/*
 * A logarithmic x axis (the view holds log10 x): ticks at 1, 2 and 5 times powers of ten; on
 * a span too short for three of them at every 1..9; on one shorter still (12 to 19 ms) at
 * five values evenly spaced on the axis, so the axis always has labels.
 */
void draw_x_log_ticks(cv::Mat &canvas, cv::Mat &plot, const cv::Rect &rect, const View &v)
{
	double lo = v.x_at(0), hi = v.x_at(rect.width);
	std::vector<double> ticks = log_ticks(lo, hi, false);
	if (ticks.size() < 3)
		ticks = log_ticks(lo, hi, true);
	if (ticks.size() < 3) {
		ticks.clear();
		for (int i = 1; i <= 5; i++)
			ticks.push_back(std::pow(10.0, lo + (hi - lo) * i / 6));
	}
	for (double t : ticks) {
		char buf[32];
		std::snprintf(buf, sizeof(buf), "%.3g", t);
		x_tick(canvas, plot, rect, (int)std::lround(v.px(std::log10(t), 0).x), buf);
	}
}

void draw_z_ticks(cv::Mat &canvas, cv::Mat &plot, const cv::Rect &rect, const View &v,
		  double step)
{
	for (long k = std::lround(std::ceil(v.z_at(rect.height) / step)); k * step <= v.z_at(0);
	     k++) {
		int w = (int)std::lround(v.px(0, k * step).y);
		cv::line(plot, {0, w}, {rect.width, w}, GRID, 1);
		std::string s = tick_label(k * step, step);
		cv::Size ts = text_size(s, 0.5);
		put_text(canvas, s, {rect.x - 8 - ts.width, rect.y + w + ts.height / 2}, 0.5);
	}
}

void draw_axis_labels(cv::Mat &canvas, const cv::Rect &rect, const std::string &xl,
		      const std::string &zl)
{
	cv::Size xs = text_size(xl, 0.65);
	put_text(canvas, xl, {rect.x + (rect.width - xs.width) / 2, rect.br().y + 50}, 0.65);

	/* putText cannot rotate: render the label on its own, turn it, paste it. */
	cv::Size zs = text_size(zl, 0.65);
	cv::Mat label(zs.height + 10, zs.width + 4, CV_8UC3, WHITE), turned;
	put_text(label, zl, {2, zs.height + 3}, 0.65);
	cv::rotate(label, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
	int top = std::max(0, rect.y + (rect.height - turned.rows) / 2);
	turned.copyTo(canvas(cv::Rect(12, top, turned.cols, turned.rows)));
}

void draw_title(cv::Mat &canvas, const char *title)
{
	double size = 0.9;
	cv::Size ts = text_size(title, size, 2);
	/* A long title shrinks rather than runs off the canvas. */
	if (ts.width > CANVAS_W - 40) {
		size *= (CANVAS_W - 40.0) / ts.width;
		ts = text_size(title, size, 2);
	}
	put_text(canvas, title, {(CANVAS_W - ts.width) / 2, 20 + ts.height}, size, 2);
}

void draw_axes(cv::Mat &canvas, const cv::Rect &rect, const View &v, const std::string &xl,
	       const std::string &zl, bool log_x = false)
{
	cv::Mat plot = canvas(rect);
	if (log_x)
		draw_x_log_ticks(canvas, plot, rect, v);
	else
		draw_x_ticks(canvas, plot, rect, v, nice_step(TICK_TARGET_PX / v.sx));
	/* A short chart panel still gets three or more ticks. */
	double z_px = std::min(TICK_TARGET_PX, rect.height / 5.0);
	draw_z_ticks(canvas, plot, rect, v, nice_step(z_px / v.sz));
	cv::rectangle(canvas, rect, BLACK, 1);
	draw_axis_labels(canvas, rect, xl, zl);
}

/* Carries the dash phase across segments so the pattern runs evenly along the whole path. */
void dashed_segment(cv::Mat &img, cv::Point2d a, cv::Point2d b, double &phase,
		    const cv::Scalar &color)
{
	const double on = 10, period = 16;
	double len = cv::norm(b - a);
	for (double s = 0; s < len;) {
		double in = std::fmod(phase + s, period);
		double e = std::min(len, s + std::max(in < on ? on - in : period - in, 1e-6));
		if (in < on)
			cv::line(img, fixed(a + (b - a) * (s / len)), fixed(a + (b - a) * (e / len)),
				 color, 2, cv::LINE_AA, SHIFT);
		s = e;
	}
	phase = std::fmod(phase + len, period);
}

void draw_path(cv::Mat &plot, const std::vector<cv::Point2d> &pts, const cv::Scalar &color,
	       bool dashed)
{
	double phase = 0;
	for (size_t i = 1; i < pts.size(); i++) {
		if (dashed)
			dashed_segment(plot, pts[i - 1], pts[i], phase, color);
		else
			cv::line(plot, fixed(pts[i - 1]), fixed(pts[i]), color, 2, cv::LINE_AA,
				 SHIFT);
	}
}

/* The start circle is larger than the end square: on a closed loop both stay visible. */
void start_marker(cv::Mat &img, cv::Point2d p, const cv::Scalar &color)
{
	cv::circle(img, fixed(p), 8 * (int)SUBPIX, color, cv::FILLED, cv::LINE_AA, SHIFT);
	cv::circle(img, fixed(p), 8 * (int)SUBPIX, BLACK, 1, cv::LINE_AA, SHIFT);
}

void end_marker(cv::Mat &img, cv::Point2d p, const cv::Scalar &color)
{
	cv::Rect box((int)std::lround(p.x) - 5, (int)std::lround(p.y) - 5, 11, 11);
	cv::rectangle(img, box, color, cv::FILLED);
	cv::rectangle(img, box, BLACK, 1);
}

/* Camera forward (third column of camera-to-world) on the ground plane; false when vertical. */
bool heading_dir(const double R[9], cv::Point2d &dir)
{
	double hx = R[2], hz = R[8], n = std::hypot(hx, hz);
	if (!(n > 1e-6))
		return false;
	dir = {hx / n, -hz / n};
	return true;
}

void point_marker(cv::Mat &img, cv::Point2d p, const cv::Scalar &color)
{
	cv::circle(img, fixed(p), 5 * (int)SUBPIX, color, cv::FILLED, cv::LINE_AA, SHIFT);
}

void arrow(cv::Mat &img, cv::Point2d from, cv::Point2d to)
{
	cv::arrowedLine(img, fixed(from), fixed(to), HEADING_COLOR, 2, cv::LINE_AA, SHIFT, 0.3);
}

enum class Glyph { LINE, DASHED, START, END, ARROW, POINT };

struct LegendEntry {
	std::string label;
	Glyph glyph;
	cv::Scalar color;
};

void draw_glyph(cv::Mat &img, const LegendEntry &e, cv::Point2d c)
{
	const cv::Point2d half(14, 0);
	double phase = 0;
	switch (e.glyph) {
	case Glyph::LINE:
		cv::line(img, fixed(c - half), fixed(c + half), e.color, 2, cv::LINE_AA, SHIFT);
		break;
	case Glyph::DASHED:
		dashed_segment(img, c - half, c + half, phase, e.color);
		break;
	case Glyph::START:
		start_marker(img, c, e.color);
		break;
	case Glyph::END:
		end_marker(img, c, e.color);
		break;
	case Glyph::ARROW:
		arrow(img, c - half, c + half);
		break;
	case Glyph::POINT:
		point_marker(img, c, e.color);
		break;
	}
}

/* Path segments crossing r: the legend goes in the corner that hides the least of the paths. */
int segments_under(const cv::Rect &r, const std::vector<cv::Point2d> &pts)
{
	int n = 0;
	for (size_t i = 1; i < pts.size(); i++) {
		cv::Point a = pts[i - 1], b = pts[i];
		n += cv::clipLine(r, a, b) ? 1 : 0;
	}
	return n;
}

using Drawn = std::vector<std::vector<cv::Point2d>>;

/* Point markers (with their numbers, 12 px around) r covers. */
int points_under(const cv::Rect &r, const std::vector<cv::Point2d> &pts)
{
	const int reach = 12;
	cv::Rect grown(r.x - reach, r.y - reach, r.width + 2 * reach, r.height + 2 * reach);
	int n = 0;
	for (const cv::Point2d &p : pts)
		n += grown.contains(cv::Point((int)p.x, (int)p.y)) ? 1 : 0;
	return n;
}

/* The corner whose legend hides the fewest path segments and point markers. */
cv::Rect legend_rect(cv::Size area, cv::Size size, const Drawn &paths,
		     const std::vector<cv::Point2d> &points)
{
	const int m = 10, right = area.width - m - size.width, bottom = area.height - m - size.height;
	const cv::Point corners[] = {{right, m}, {m, m}, {right, bottom}, {m, bottom}};
	cv::Rect best;
	int best_hits = -1;
	for (const cv::Point &c : corners) {
		cv::Rect r(c, size);
		int hits = points_under(r, points);
		for (const auto &p : paths)
			hits += segments_under(r, p);
		if (best_hits < 0 || hits < best_hits) {
			best = r;
			best_hits = hits;
		}
	}
	return best;
}

void draw_legend(cv::Mat &plot, const std::vector<LegendEntry> &entries, const Drawn &paths,
		 const std::vector<cv::Point2d> &points = {})
{
	const int row_h = 26, glyph_w = 40, pad = 10;
	int text_w = 0;
	for (const LegendEntry &e : entries)
		text_w = std::max(text_w, text_size(e.label, 0.55).width);
	cv::Size size(pad + glyph_w + 8 + text_w + pad, 2 * pad + row_h * (int)entries.size() - 6);
	cv::Rect r = legend_rect(plot.size(), size, paths, points);

	cv::rectangle(plot, r, WHITE, cv::FILLED);
	cv::rectangle(plot, r, NEUTRAL, 1);
	for (size_t i = 0; i < entries.size(); i++) {
		int cy = r.y + pad + 10 + row_h * (int)i;
		draw_glyph(plot, entries[i], cv::Point2d(r.x + pad + glyph_w / 2.0, cy));
		put_text(plot, entries[i].label, {r.x + pad + glyph_w + 8, cy + 6}, 0.55);
	}
}

/* A run whose every pose failed still gets a plot that says so, not a blank grid. */
void draw_no_data(cv::Mat &plot, const std::string &s)
{
	cv::Size ts = text_size(s, 0.8);
	put_text(plot, s, {(plot.cols - ts.width) / 2, (plot.rows + ts.height) / 2}, 0.8, 1, NEUTRAL);
}

void draw_paths(cv::Mat &plot, const std::vector<cv::Point2d> &est,
		const std::vector<cv::Point2d> &gt, const double *heading,
		std::vector<LegendEntry> &legend)
{
	legend.push_back({"estimate", Glyph::LINE, EST_COLOR});
	if (!gt.empty())
		legend.push_back({"ground truth", Glyph::DASHED, GT_COLOR});
	draw_path(plot, gt, GT_COLOR, true);
	draw_path(plot, est, EST_COLOR, false);
	if (!est.empty() || !gt.empty()) {
		start_marker(plot, est.empty() ? gt.front() : est.front(), START_COLOR);
		legend.push_back({"start", Glyph::START, START_COLOR});
		legend.push_back({"end", Glyph::END, NEUTRAL});
	}
	if (!gt.empty())
		end_marker(plot, gt.back(), GT_COLOR);
	if (!est.empty())
		end_marker(plot, est.back(), EST_COLOR);
	cv::Point2d dir;
	if (heading && !est.empty() && heading_dir(heading, dir)) {
		arrow(plot, est.back(), est.back() + dir * ARROW_PX);
		legend.push_back({"heading", Glyph::ARROW, HEADING_COLOR});
	}
}

/*
 * Paints every pixel of canvas (CANVAS_H x CANVAS_W, BGR), which may be the caller's memory;
 * unit: of the axes.
 */
void draw_topdown(cv::Mat &canvas, const char *title, const Path &est, const double *heading,
		  const Path &gt, const std::string &unit)
{
	canvas.setTo(WHITE);
	/* Data is drawn in this view, so nothing spills over the ticks and labels. */
	cv::Mat plot = canvas(PLOT_RECT);
	View v = fit_view(est, gt);
	std::vector<cv::Point2d> est_px = project(v, est), gt_px = project(v, gt);
	std::vector<LegendEntry> legend;

	draw_axes(canvas, PLOT_RECT, v, "x [" + unit + "]", "z [" + unit + "]");
	draw_paths(plot, est_px, gt_px, heading, legend);
	if (est_px.empty() && gt_px.empty())
		draw_no_data(plot, "no valid poses");
	draw_legend(plot, legend, {est_px, gt_px});
	if (title)
		draw_title(canvas, title);
}

cv::Mat render(const char *title, const Path &est, const double *heading, const Path &gt,
	       const char *unit)
{
	cv::Mat canvas(CANVAS_H, CANVAS_W, CV_8UC3);
	draw_topdown(canvas, title, est, heading, gt, unit);
	return canvas;
}

/* ".png" of "dir/name.png"; empty when the file name has no extension. */
std::string extension_of(const std::string &path)
{
	size_t slash = path.rfind('/'), dot = path.rfind('.');
	size_t base = slash == std::string::npos ? 0 : slash + 1;
	return dot == std::string::npos || dot <= base ? std::string() : path.substr(dot);
}

bool can_write(const char *path)
{
	return !extension_of(path).empty() && cv::haveImageWriter(path);
}

int write_image(const char *path, const cv::Mat &bgr)
{
	mvod_image img = {bgr.cols, bgr.rows, (int)bgr.step, MVOD_PIX_BGR, bgr.data};
	return mvod_image_file_write(path, extension_of(path).c_str(), &img, 0);
}

int plot_topdown(const char *path, const char *title, const Path &est, const double *heading,
		 const Path &gt, const char *unit)
{
	if (!can_write(path))
		return -EINVAL;
	return write_image(path, render(title, est, heading, gt, unit));
}

/* --- charts: panels of x-y series --- */

const cv::Scalar PALETTE[] = {EST_COLOR, GT_COLOR, cv::Scalar(40, 40, 200), START_COLOR,
			      cv::Scalar(0, 140, 230)};
const int CHART_LEFT = 90, CHART_RIGHT = 30, CHART_TOP = 60, CHART_BOTTOM = 70, CHART_GAP = 10;

cv::Scalar series_color(int i)
{
	return PALETTE[i % (int)(sizeof(PALETTE) / sizeof(PALETTE[0]))];
}

/* The x a panel draws: log10 x on a logarithmic axis. */
double chart_x(const mvod_plot_panel &p, double x)
{
	return p.log_x ? std::log10(x) : x;
}

/* A point that can be drawn: finite, and x > 0 on a logarithmic axis. */
bool finite_at(const mvod_plot_panel &p, const mvod_plot_series &s, int i)
{
	return std::isfinite(chart_x(p, s.x[i])) && std::isfinite(s.y[i]);
}

/* Axes that hold every finite point, y from 0 when nothing is negative, with a margin. */
View fit_chart(const mvod_plot_panel &p, cv::Size area)
{
	cv::Point2d lo(HUGE_VAL, HUGE_VAL), hi(-HUGE_VAL, -HUGE_VAL);
	for (int k = 0; k < p.n_series; k++)
		for (int i = 0; i < p.series[k].n; i++)
			if (finite_at(p, p.series[k], i)) {
				double x = chart_x(p, p.series[k].x[i]), y = p.series[k].y[i];
				lo = {std::min(lo.x, x), std::min(lo.y, y)};
				hi = {std::max(hi.x, x), std::max(hi.y, y)};
			}
	if (lo.x > hi.x)
		lo = hi = cv::Point2d(0, 0);
	if (lo.y > 0)
		lo.y = 0;
	/* Flat data still gets a unit range. */
	double span_x = hi.x > lo.x ? hi.x - lo.x : 1, span_y = hi.y > lo.y ? hi.y - lo.y : 1;
	double sx = (area.width - 2 * PAD_PX) / span_x, sy = (area.height - 2 * PAD_PX) / span_y;
	return {(lo.x + hi.x) / 2, (lo.y + hi.y) / 2, sx, sy, area.width, area.height};
}

/*
 * Labelled points are numbered on the plot and named in a key beside it: the number goes in
 * the first of eight places around its marker that overlaps no marker or number yet drawn.
 */
void place_number(cv::Mat &plot, cv::Point2d p, const std::string &num,
		  std::vector<cv::Rect> &taken)
{
	cv::Size ts = text_size(num, 0.45);
	const double w = ts.width, h = ts.height;
	const cv::Point2d offs[] = {{7, -7},	     {7, 7 + h},	{-7 - w, -7},
				    {-7 - w, 7 + h}, {-w / 2, -9},	{-w / 2, 9 + h},
				    {14, h / 2},     {-14 - w, h / 2}};
	cv::Rect inside(0, 0, plot.cols, plot.rows), best;
	for (const cv::Point2d &o : offs) {
		cv::Rect r((int)(p.x + o.x), (int)(p.y + o.y) - ts.height, ts.width, ts.height);
		bool free = (r & inside) == r;
		for (const cv::Rect &t : taken)
			free = free && (r & t).empty();
		if (free || best.empty())
			best = r;
		if (free)
			break;
	}
	taken.push_back(best);
	put_text(plot, num, {best.x, best.br().y}, 0.45);
}

/* Draws s; returns its line's pixels, or for points their markers' (in points). */
std::vector<cv::Point2d> draw_series(cv::Mat &plot, const View &v, const mvod_plot_panel &p,
				     const mvod_plot_series &s, const cv::Scalar &color,
				     std::vector<cv::Point2d> &points)
{
	std::vector<cv::Point2d> px;
	std::vector<int> index;
	for (int i = 0; i < s.n; i++)
		if (finite_at(p, s, i)) {
			px.push_back(v.px(chart_x(p, s.x[i]), s.y[i]));
			index.push_back(i);
		}
	if (s.style != MVOD_PLOT_POINTS) {
		draw_path(plot, px, color, s.style == MVOD_PLOT_DASHED);
		return px;
	}
	std::vector<cv::Rect> taken;
	for (const cv::Point2d &q : px) {
		point_marker(plot, q, color);
		taken.emplace_back((int)q.x - 5, (int)q.y - 5, 11, 11);
	}
	for (size_t j = 0; s.point_labels && j < px.size(); j++)
		place_number(plot, px[j], std::to_string(index[j] + 1), taken);
	points.insert(points.end(), px.begin(), px.end());
	return {};
}

const int KEY_W = 300; /* room right of a panel for the key of numbered points */

bool has_key(const mvod_plot_panel &p)
{
	for (int k = 0; k < p.n_series; k++)
		if (p.series[k].style == MVOD_PLOT_POINTS && p.series[k].point_labels)
			return true;
	return false;
}

/* "N  label" for every labelled point, top down beside the plot. */
void draw_key(cv::Mat &canvas, const cv::Rect &rect, const mvod_plot_panel &p)
{
	int y = rect.y + 14;
	for (int k = 0; k < p.n_series; k++)
		for (int i = 0; p.series[k].point_labels && i < p.series[k].n; i++) {
			std::string line = std::to_string(i + 1) + "  " +
					   (p.series[k].point_labels[i] ? p.series[k].point_labels[i] : "");
			if (!finite_at(p, p.series[k], i))
				line += " (not drawn)";
			put_text(canvas, line, {rect.br().x + 12, y}, 0.42);
			y += 18;
		}
}

void draw_panel(cv::Mat &canvas, const cv::Rect &rect, const mvod_plot_panel &p)
{
	View v = fit_chart(p, rect.size());
	cv::Mat plot = canvas(rect);
	draw_axes(canvas, rect, v, p.x_label ? p.x_label : "", p.y_label ? p.y_label : "",
		  p.log_x);
	if (has_key(p))
		draw_key(canvas, rect, p);
	Drawn drawn;
	std::vector<cv::Point2d> points;
	std::vector<LegendEntry> legend;
	bool any = false;
	for (int k = 0; k < p.n_series; k++)
		for (int i = 0; i < p.series[k].n; i++)
			any = any || finite_at(p, p.series[k], i);
	if (!any) {
		draw_no_data(plot, "no data");
		return;
	}
	for (int k = 0; k < p.n_series; k++) {
		const mvod_plot_series &s = p.series[k];
		drawn.push_back(draw_series(plot, v, p, s, series_color(k), points));
		Glyph g = s.style == MVOD_PLOT_POINTS	? Glyph::POINT
			  : s.style == MVOD_PLOT_DASHED ? Glyph::DASHED
							: Glyph::LINE;
		legend.push_back({s.label ? s.label : "", g, series_color(k)});
	}
	draw_legend(plot, legend, drawn, points);
}

cv::Mat render_chart(const char *title, const mvod_plot_panel *panels, int n)
{
	/* One panel gets a square-ish area; stacked panels share the height of three. */
	int panel_h = n == 1 ? 640 : std::max(200, 780 / n);
	int h = CHART_TOP + n * (panel_h + CHART_BOTTOM + CHART_GAP);
	cv::Mat canvas(h, CANVAS_W, CV_8UC3, WHITE);
	for (int i = 0; i < n; i++) {
		int key = has_key(panels[i]) ? KEY_W : 0;
		cv::Rect r(CHART_LEFT, CHART_TOP + i * (panel_h + CHART_BOTTOM + CHART_GAP),
			   CANVAS_W - CHART_LEFT - CHART_RIGHT - key, panel_h);
		draw_panel(canvas, r, panels[i]);
	}
	if (title)
		draw_title(canvas, title);
	return canvas;
}

bool valid_panels(const mvod_plot_panel *panels, int n)
{
	if (!panels || n < 1 || n > 8)
		return false;
	for (int i = 0; i < n; i++)
		for (int k = 0; k < panels[i].n_series; k++) {
			const mvod_plot_series &s = panels[i].series[k];
			if (s.n < 0 || (s.n > 0 && (!s.x || !s.y)))
				return false;
		}
	return true;
}

bool paths_ok(const double *est_xyz, int n_est, const double *gt_xyz, int n_gt)
{
	return n_est >= 0 && n_gt >= 0 && (n_est == 0 || est_xyz) && (n_gt == 0 || gt_xyz);
}

} // namespace

extern "C" const char *mvod_plot_unit(bool metric)
{
	return metric ? "m" : "units, free scale";
}

extern "C" int mvod_plot_topdown(const char *path, const char *title, const double *est_xyz,
				 int n_est, const double heading[9], const double *gt_xyz, int n_gt,
				 const char *unit)
{
	if (!path || !unit || !paths_ok(est_xyz, n_est, gt_xyz, n_gt))
		return -EINVAL;
	return mvod_guarded([&] {
		return plot_topdown(path, title, {est_xyz, n_est}, heading, {gt_xyz, n_gt}, unit);
	});
}

extern "C" int mvod_plot_check(const char *what, const char *path, char *err, size_t errlen)
{
	return mvod_guarded([&] {
		if (can_write(path))
			return 0;
		std::string ext = extension_of(path);
		std::string why = ext.empty() ? "no extension names the image format"
					      : "OpenCV writes no " + ext + " images";
		return mvod_errf(err, errlen, -EINVAL, "%s %s: %s: name a FILE.png (or .jpg, .bmp, "
				 ".tif, .ppm)", what, path, why.c_str());
	});
}

extern "C" int mvod_plot_topdown_draw(struct mvod_image *out, const char *title,
				      const double *est_xyz, int n_est, const double heading[9],
				      const double *gt_xyz, int n_gt, const char *unit)
{
	if (!unit || !out || !out->data || out->fmt != MVOD_PIX_BGR || out->w != CANVAS_W ||
	    out->h != CANVAS_H || !paths_ok(est_xyz, n_est, gt_xyz, n_gt))
		return -EINVAL;
	return mvod_guarded([&] {
		/* Straight into the caller's pixels: a redraw allocates no canvas of its own. */
		cv::Mat dst(out->h, out->w, CV_8UC3, out->data, (size_t)out->stride);
		draw_topdown(dst, title, {est_xyz, n_est}, heading, {gt_xyz, n_gt}, unit);
		return 0;
	});
}

extern "C" int mvod_plot_chart(const char *path, const char *title,
			       const struct mvod_plot_panel *panels, int n_panels)
{
	if (!path || !valid_panels(panels, n_panels))
		return -EINVAL;
	return mvod_guarded([&] {
		if (!can_write(path))
			return -EINVAL;
		return write_image(path, render_chart(title, panels, n_panels));
	});
}

extern "C" double mvod_plot_nice_step(double raw)
{
	double p = std::pow(10.0, std::floor(std::log10(raw)));
	double f = raw / p;
	return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * p;
}

extern "C" void mvod_plot_tick_label(double value, double step, char *buf, size_t len)
{
	int decimals = step >= 1 ? 0 : (int)std::ceil(-std::log10(step) - 1e-9);
	/* Avoids "-0.0" at the origin. */
	if (std::fabs(value) < step * 1e-6)
		value = 0;
	std::snprintf(buf, len, "%.*f", decimals, value);
}

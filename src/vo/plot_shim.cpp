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

#include "util/atomic_file.h"
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

/* World (x, z) in metres to pixels of the plot area: x right, z (forward) up, equal aspect. */
struct View {
	double cx, cz, scale;
	cv::Point2d px(double x, double z) const
	{
		return {PLOT_RECT.width / 2.0 + (x - cx) * scale,
			PLOT_RECT.height / 2.0 - (z - cz) * scale};
	}
	double x_at(double u) const { return cx + (u - PLOT_RECT.width / 2.0) / scale; }
	double z_at(double v) const { return cz - (v - PLOT_RECT.height / 2.0) / scale; }
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
	return {(lo.x + hi.x) / 2, (lo.y + hi.y) / 2, scale};
}

/* The smallest 1, 2 or 5 x 10^k that is at least raw. */
double nice_step(double raw)
{
	double p = std::pow(10.0, std::floor(std::log10(raw)));
	double f = raw / p;
	return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * p;
}

std::string tick_label(double value, double step)
{
	int decimals = step >= 1 ? 0 : (int)std::ceil(-std::log10(step) - 1e-9);
	/* Avoids "-0.0" at the origin. */
	if (std::fabs(value) < step * 1e-6)
		value = 0;
	char buf[32];
	std::snprintf(buf, sizeof(buf), "%.*f", decimals, value);
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

void draw_x_ticks(cv::Mat &canvas, cv::Mat &plot, const View &v, double step)
{
	for (long k = std::lround(std::ceil(v.x_at(0) / step));
	     k * step <= v.x_at(PLOT_RECT.width); k++) {
		int u = (int)std::lround(v.px(k * step, 0).x);
		cv::line(plot, {u, 0}, {u, PLOT_RECT.height}, GRID, 1);
		std::string s = tick_label(k * step, step);
		cv::Size ts = text_size(s, 0.5);
		put_text(canvas, s, {PLOT_RECT.x + u - ts.width / 2, PLOT_RECT.br().y + 22}, 0.5);
	}
}

void draw_z_ticks(cv::Mat &canvas, cv::Mat &plot, const View &v, double step)
{
	for (long k = std::lround(std::ceil(v.z_at(PLOT_RECT.height) / step));
	     k * step <= v.z_at(0); k++) {
		int w = (int)std::lround(v.px(0, k * step).y);
		cv::line(plot, {0, w}, {PLOT_RECT.width, w}, GRID, 1);
		std::string s = tick_label(k * step, step);
		cv::Size ts = text_size(s, 0.5);
		put_text(canvas, s, {PLOT_RECT.x - 8 - ts.width, PLOT_RECT.y + w + ts.height / 2},
			 0.5);
	}
}

void draw_axis_labels(cv::Mat &canvas)
{
	const std::string xl = "x [m]", zl = "z [m]";
	cv::Size xs = text_size(xl, 0.65);
	put_text(canvas, xl, {PLOT_RECT.x + (PLOT_RECT.width - xs.width) / 2, CANVAS_H - 20},
		 0.65);

	/* putText cannot rotate: render the label on its own, turn it, paste it. */
	cv::Size zs = text_size(zl, 0.65);
	cv::Mat label(zs.height + 10, zs.width + 4, CV_8UC3, WHITE), turned;
	put_text(label, zl, {2, zs.height + 3}, 0.65);
	cv::rotate(label, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
	turned.copyTo(canvas(cv::Rect(12, PLOT_RECT.y + (PLOT_RECT.height - turned.rows) / 2,
				      turned.cols, turned.rows)));
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

void draw_axes(cv::Mat &canvas, cv::Mat &plot, const View &v)
{
	double step = nice_step(TICK_TARGET_PX / v.scale);
	draw_x_ticks(canvas, plot, v, step);
	draw_z_ticks(canvas, plot, v, step);
	cv::rectangle(canvas, PLOT_RECT, BLACK, 1);
	draw_axis_labels(canvas);
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

void arrow(cv::Mat &img, cv::Point2d from, cv::Point2d to)
{
	cv::arrowedLine(img, fixed(from), fixed(to), HEADING_COLOR, 2, cv::LINE_AA, SHIFT, 0.3);
}

enum class Glyph { LINE, DASHED, START, END, ARROW };

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

cv::Rect legend_rect(cv::Size size, const std::vector<cv::Point2d> &est,
		     const std::vector<cv::Point2d> &gt)
{
	const int m = 10, right = PLOT_RECT.width - m - size.width,
		  bottom = PLOT_RECT.height - m - size.height;
	const cv::Point corners[] = {{right, m}, {m, m}, {right, bottom}, {m, bottom}};
	cv::Rect best;
	int best_hits = -1;
	for (const cv::Point &c : corners) {
		cv::Rect r(c, size);
		int hits = segments_under(r, est) + segments_under(r, gt);
		if (best_hits < 0 || hits < best_hits) {
			best = r;
			best_hits = hits;
		}
	}
	return best;
}

void draw_legend(cv::Mat &plot, const std::vector<LegendEntry> &entries,
		 const std::vector<cv::Point2d> &est, const std::vector<cv::Point2d> &gt)
{
	const int row_h = 26, glyph_w = 40, pad = 10;
	int text_w = 0;
	for (const LegendEntry &e : entries)
		text_w = std::max(text_w, text_size(e.label, 0.55).width);
	cv::Size size(pad + glyph_w + 8 + text_w + pad, 2 * pad + row_h * (int)entries.size() - 6);
	cv::Rect r = legend_rect(size, est, gt);

	cv::rectangle(plot, r, WHITE, cv::FILLED);
	cv::rectangle(plot, r, NEUTRAL, 1);
	for (size_t i = 0; i < entries.size(); i++) {
		int cy = r.y + pad + 10 + row_h * (int)i;
		draw_glyph(plot, entries[i], cv::Point2d(r.x + pad + glyph_w / 2.0, cy));
		put_text(plot, entries[i].label, {r.x + pad + glyph_w + 8, cy + 6}, 0.55);
	}
}

/* A run whose every pose failed still gets a plot that says so, not a blank grid. */
void draw_no_data(cv::Mat &plot)
{
	const std::string s = "no valid poses";
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

cv::Mat render(const char *title, const Path &est, const double *heading, const Path &gt)
{
	cv::Mat canvas(CANVAS_H, CANVAS_W, CV_8UC3, WHITE);
	/* Data is drawn in this view, so nothing spills over the ticks and labels. */
	cv::Mat plot = canvas(PLOT_RECT);
	View v = fit_view(est, gt);
	std::vector<cv::Point2d> est_px = project(v, est), gt_px = project(v, gt);
	std::vector<LegendEntry> legend;

	draw_axes(canvas, plot, v);
	draw_paths(plot, est_px, gt_px, heading, legend);
	if (est_px.empty() && gt_px.empty())
		draw_no_data(plot);
	draw_legend(plot, legend, est_px, gt_px);
	if (title)
		draw_title(canvas, title);
	return canvas;
}

/* ".png" of "dir/name.png"; empty when the file name has no extension. */
std::string extension_of(const std::string &path)
{
	size_t slash = path.rfind('/'), dot = path.rfind('.');
	size_t base = slash == std::string::npos ? 0 : slash + 1;
	return dot == std::string::npos || dot <= base ? std::string() : path.substr(dot);
}

int plot_topdown(const char *path, const char *title, const Path &est, const double *heading,
		 const Path &gt)
{
	std::string ext = extension_of(path);
	if (ext.empty() || !cv::haveImageWriter(path))
		return -EINVAL;
	/* Encoded before any file exists, so an encoder error leaves nothing behind. */
	std::vector<uchar> png;
	if (!cv::imencode(ext, render(title, est, heading, gt), png))
		return -EIO;
	return mvod_write_replace(path, png.data(), png.size());
}

bool paths_ok(const double *est_xyz, int n_est, const double *gt_xyz, int n_gt)
{
	return n_est >= 0 && n_gt >= 0 && (n_est == 0 || est_xyz) && (n_gt == 0 || gt_xyz);
}

} // namespace

extern "C" int mvod_plot_topdown(const char *path, const char *title, const double *est_xyz,
				 int n_est, const double heading[9], const double *gt_xyz, int n_gt)
{
	if (!path || !paths_ok(est_xyz, n_est, gt_xyz, n_gt))
		return -EINVAL;
	return mvod_guarded(
		[&] { return plot_topdown(path, title, {est_xyz, n_est}, heading, {gt_xyz, n_gt}); });
}

extern "C" int mvod_plot_topdown_draw(struct mvod_image *out, const char *title,
				      const double *est_xyz, int n_est, const double heading[9],
				      const double *gt_xyz, int n_gt)
{
	if (!out || !out->data || out->fmt != MVOD_PIX_BGR || out->w != CANVAS_W ||
	    out->h != CANVAS_H || !paths_ok(est_xyz, n_est, gt_xyz, n_gt))
		return -EINVAL;
	return mvod_guarded([&] {
		cv::Mat dst(out->h, out->w, CV_8UC3, out->data, (size_t)out->stride);
		render(title, {est_xyz, n_est}, heading, {gt_xyz, n_gt}).copyTo(dst);
		return 0;
	});
}

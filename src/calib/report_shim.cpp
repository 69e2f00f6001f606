/* The calibration report: one PNG a user can read without knowing OpenCV. */
#include "calib/calib_shim.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "mvod/calibrate.h"
#include "mvod/plot.h"
#include "util/image_file.h"
#include "util/shim_guard.hpp"

namespace {

/* Four panels of PANEL_W x PANEL_H in two rows, each under a title line. */
/* The header: the intrinsics, the verdict, and up to two lines of its advice. */
const int PANEL_W = 600, PANEL_H = 450, GAP = 20, TITLE_H = 30, HEADER_H = 120;
const int ADVICE_LINES = 2;
const double ADVICE_FONT = 0.5;
const int CANVAS_W = 2 * PANEL_W + 3 * GAP;
const int CANVAS_H = HEADER_H + 2 * (TITLE_H + PANEL_H + GAP);
const int FONT = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar WHITE(255, 255, 255), BLACK(0, 0, 0), GRID(200, 200, 200), BAR(190, 120, 40),
	LIMIT(40, 40, 210), GOOD(40, 140, 40);

cv::Rect panel(int col, int row)
{
	return {GAP + col * (PANEL_W + GAP), HEADER_H + row * (TITLE_H + PANEL_H + GAP) + TITLE_H,
		PANEL_W, PANEL_H};
}

void title(cv::Mat &c, cv::Rect p, const std::string &text)
{
	cv::putText(c, text, {p.x, p.y - 9}, FONT, 0.55, BLACK, 1, cv::LINE_AA);
}

/* The image's w x h fitted into the panel, centred. */
cv::Rect fit_rect(cv::Rect p, int w, int h)
{
	double s = std::min((double)p.width / w, (double)p.height / h);
	int fw = (int)(w * s), fh = (int)(h * s);
	return {p.x + (p.width - fw) / 2, p.y + (p.height - fh) / 2, fw, fh};
}

cv::Scalar view_colour(int i, int n)
{
	cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(170.0 * i / std::max(1, n), 220, 220)), bgr;
	cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
	cv::Vec3b v = bgr.at<cv::Vec3b>(0, 0);
	return {(double)v[0], (double)v[1], (double)v[2]};
}

void draw_coverage(cv::Mat &c, const mvod_calib_report &r)
{
	cv::Rect p = panel(0, 0);
	int w = r.cam->width, h = r.cam->height;
	char buf[128];
	std::snprintf(buf, sizeof(buf), "Corners of the %d views used (%.0f %% of image cells)", r.n,
		      100.0 * r.coverage);
	title(c, p, buf);
	cv::Rect f = fit_rect(p, w, h);
	c(f).setTo(cv::Scalar(60, 60, 60));
	double s = (double)f.width / w;
	for (int k = 1; k < MVOD_CALIB_CELLS_X; k++)
		cv::line(c, {f.x + f.width * k / MVOD_CALIB_CELLS_X, f.y},
			 {f.x + f.width * k / MVOD_CALIB_CELLS_X, f.y + f.height - 1}, cv::Scalar(90, 90, 90));
	for (int k = 1; k < MVOD_CALIB_CELLS_Y; k++)
		cv::line(c, {f.x, f.y + f.height * k / MVOD_CALIB_CELLS_Y},
			 {f.x + f.width - 1, f.y + f.height * k / MVOD_CALIB_CELLS_Y}, cv::Scalar(90, 90, 90));
	for (int i = 0; i < r.n; i++) {
		cv::Scalar col = view_colour(i, r.n);
		for (int k = 0; k < r.views[i].n; k++)
			cv::circle(c, {f.x + (int)(r.views[i].xy[2 * k] * s), f.y + (int)(r.views[i].xy[2 * k + 1] * s)},
				   2, col, cv::FILLED, cv::LINE_AA);
	}
	std::snprintf(buf, sizeof(buf), "%d x %d px", w, h);
	cv::putText(c, buf, {f.x + 6, f.y + f.height - 8}, FONT, 0.45, WHITE, 1, cv::LINE_AA);
}

void draw_errors(cv::Mat &c, const mvod_calib_report &r)
{
	cv::Rect p = panel(1, 0);
	title(c, p, "Reprojection error per view (RMS, px); red: outlier limit");
	cv::Rect a(p.x + 50, p.y + 10, p.width - 60, p.height - 50);
	double top = r.outlier_px;
	for (int i = 0; i < r.n; i++)
		top = std::max(top, r.view_rms_px[i]);
	top = top > 0 ? top * 1.1 : 1.0;
	/* Four or five ticks at a round step (0.1, 0.2, 0.5, ...), the axis up to the next one. */
	double step = mvod_plot_nice_step(top / 5);
	top = step * std::ceil(top / step - 1e-9);
	auto y_of = [&](double v) { return a.y + a.height - (int)std::lround(v / top * a.height); };
	for (int k = 0; k * step <= top * (1 + 1e-9); k++) {
		double v = k * step;
		cv::line(c, {a.x, y_of(v)}, {a.x + a.width, y_of(v)}, GRID);
		char buf[32];
		mvod_plot_tick_label(v, step, buf, sizeof(buf));
		cv::putText(c, buf, {p.x, y_of(v) + 4}, FONT, 0.4, BLACK, 1, cv::LINE_AA);
	}
	double bw = (double)a.width / std::max(1, r.n);
	for (int i = 0; i < r.n; i++) {
		int x0 = a.x + (int)(i * bw), x1 = a.x + std::max((int)((i + 1) * bw) - 1, (int)(i * bw) + 1);
		cv::rectangle(c, cv::Point(x0, y_of(r.view_rms_px[i])), cv::Point(x1, y_of(0)), BAR, cv::FILLED);
	}
	cv::line(c, {a.x, y_of(r.outlier_px)}, {a.x + a.width, y_of(r.outlier_px)}, LIMIT, 2);
	cv::rectangle(c, a, BLACK);
	char buf[64];
	std::snprintf(buf, sizeof(buf), "view (1..%d, in selection order)", r.n);
	cv::putText(c, buf, {a.x + a.width / 2 - 110, a.y + a.height + 28}, FONT, 0.45, BLACK, 1, cv::LINE_AA);
}

cv::Mat undistorted(const cv::Mat &src, const mvod_camera &cam)
{
	cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
	cv::Mat D(1, cam.n_dist, CV_64F, const_cast<double *>(cam.dist)), out;
	if (cam.model == MVOD_CAM_FISHEYE_KB4)
		cv::fisheye::undistortImage(src, out, K, D, K);
	else
		cv::undistort(src, out, K, D);
	return out;
}

void draw_frame(cv::Mat &c, cv::Rect p, const cv::Mat &img, const std::string &text)
{
	title(c, p, text);
	cv::Rect f = fit_rect(p, img.cols, img.rows);
	cv::Mat bgr;
	if (img.channels() == 1)
		cv::cvtColor(img, bgr, cv::COLOR_GRAY2BGR);
	else
		bgr = img;
	cv::resize(bgr, c(f), f.size(), 0, 0, cv::INTER_AREA);
}

void draw_samples(cv::Mat &c, const mvod_calib_report &r)
{
	if (!r.sample) {
		title(c, panel(0, 1), "No sample frame");
		return;
	}
	const mvod_image &s = *r.sample;
	cv::Mat img(s.h, s.w, s.fmt == MVOD_PIX_BGR ? CV_8UC3 : CV_8UC1, s.data, (size_t)s.stride);
	draw_frame(c, panel(0, 1), img, "A frame as recorded");
	draw_frame(c, panel(1, 1), undistorted(img, *r.cam),
		   std::string("Undistorted (") + mvod_cam_model_name(r.cam->model) +
			   "): straight edges should look straight");
}

/* The longest prefix of s, cut at a blank, that is at most width pixels wide in the advice font. */
size_t fit_words(const std::string &s, int width)
{
	int base;
	size_t cut = s.size();
	while (cut > 0 && cv::getTextSize(s.substr(0, cut), FONT, ADVICE_FONT, 1, &base).width > width) {
		size_t sp = s.rfind(' ', cut - 1);
		cut = sp == std::string::npos ? 0 : sp;
	}
	return cut;
}

/* The verdict in colour (green: good), and its advice wrapped at blanks ("..." when cut). */
void draw_verdict(cv::Mat &c, const mvod_calib_report &r)
{
	std::string head = std::string("verdict: ") + mvod_calib_verdict_name(r.verdict);
	cv::putText(c, head, {GAP, 62}, FONT, 0.7, r.verdict == MVOD_VERDICT_GOOD ? GOOD : LIMIT,
		    2, cv::LINE_AA);
	std::string rest = r.advice ? r.advice : "";
	const int width = CANVAS_W - 2 * GAP, ellipsis = 30;
	for (int line = 0; line < ADVICE_LINES && !rest.empty(); line++) {
		bool last = line == ADVICE_LINES - 1;
		size_t cut = fit_words(rest, width);
		std::string text = rest.substr(0, cut);
		if (last && cut < rest.size())
			text = rest.substr(0, fit_words(rest, width - ellipsis)) + " ...";
		cv::putText(c, text, {GAP, 86 + 20 * line}, FONT, ADVICE_FONT, BLACK, 1, cv::LINE_AA);
		rest = cut < rest.size() ? rest.substr(cut + 1) : "";
	}
}

} // namespace

extern "C" int mvod_calib_report_write(const char *path, const struct mvod_calib_report *r)
{
	if (r->n < 1 || r->cam->width < 1 || r->cam->height < 1)
		return -EINVAL;
	return mvod_guarded([&] {
		cv::Mat c(CANVAS_H, CANVAS_W, CV_8UC3, WHITE);
		char head[160];
		std::snprintf(head, sizeof(head), "mvod calibrate: %s, fx %.1f fy %.1f cx %.1f cy %.1f px",
			      mvod_cam_model_name(r->cam->model), r->cam->fx, r->cam->fy, r->cam->cx,
			      r->cam->cy);
		cv::putText(c, head, {GAP, 30}, FONT, 0.7, BLACK, 2, cv::LINE_AA);
		draw_verdict(c, *r);
		draw_coverage(c, *r);
		draw_errors(c, *r);
		draw_samples(c, *r);
		mvod_image view = {c.cols, c.rows, (int)c.step, MVOD_PIX_BGR, c.data};
		return mvod_image_file_write(path, ".png", &view, 0);
	});
}

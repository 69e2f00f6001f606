#include "cv_shim.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>
#include <opencv2/imgproc.hpp>

#include "util/shim_guard.hpp"


static cv::Mat view(const struct mvod_image *img)
{
	int type = img->fmt == MVOD_PIX_GREY ? CV_8UC1 : CV_8UC3;
	return cv::Mat(img->h, img->w, type, img->data, (size_t)img->stride);
}

static struct mvod_image image_of(cv::Mat &m)
{
	return {m.cols, m.rows, (int)m.step[0], MVOD_PIX_GREY, m.data};
}

struct mvod_cv_preproc {
	int in_w, in_h, out_w, out_h;
	int blur_ksize;
	bool remap; /* undistortion (and resize) through maps computed once */
	cv::Mat map1, map2;
	cv::Mat grey, scaled, blurred;
};

static cv::Matx33d K_of(const struct mvod_camera *cam)
{
	cv::Matx33d K;
	mvod_camera_K(cam, K.val);
	return K;
}

static void build_maps(mvod_cv_preproc *p, const struct mvod_camera *cam, const cv::Matx33d &Knew)
{
	const cv::Matx33d K = K_of(cam);
	cv::Mat D(1, cam->n_dist, CV_64F, const_cast<double *>(cam->dist));
	cv::Size size(p->out_w, p->out_h);
	if (cam->model == MVOD_CAM_FOV) {
		/* No FOV lens in OpenCV: camera/lens.c's closed form, stored as OpenCV's below. */
		cv::Mat mx(size, CV_32FC1), my(size, CV_32FC1);
		mvod_camera_undistort_maps(cam, Knew.val, size.width, size.height, mx.ptr<float>(),
					   my.ptr<float>());
		cv::convertMaps(mx, my, p->map1, p->map2, CV_16SC2);
	} else if (cam->model == MVOD_CAM_FISHEYE_KB4)
		cv::fisheye::initUndistortRectifyMap(K, D, cv::Matx33d::eye(), Knew, size, CV_16SC2,
						     p->map1, p->map2);
	else
		cv::initUndistortRectifyMap(K, D, cv::noArray(), Knew, size, CV_16SC2, p->map1,
					    p->map2);
}

extern "C" int mvod_cv_preproc_create(const struct mvod_camera *cam, double resize, int blur_ksize,
				      struct mvod_camera *out_cam, struct mvod_cv_preproc **out)
{
	if (cam->width <= 0 || cam->height <= 0 || !(resize > 0 && resize <= 1) ||
	    (blur_ksize && (blur_ksize < 0 || blur_ksize % 2 == 0)))
		return -EINVAL;
	return mvod_guarded([&] {
		auto p = std::make_unique<mvod_cv_preproc>();
		p->in_w = cam->width;
		p->in_h = cam->height;
		p->out_w = (int)(cam->width * resize + 0.5);
		p->out_h = (int)(cam->height * resize + 0.5);
		p->blur_ksize = blur_ksize;
		double sx = (double)p->out_w / cam->width, sy = (double)p->out_h / cam->height;
		/* Pixel centres scale about -0.5 so that resize keeps the principal point honest. */
		struct mvod_camera c = {};
		c.width = p->out_w;
		c.height = p->out_h;
		c.fx = cam->fx * sx;
		c.fy = cam->fy * sy;
		c.cx = (cam->cx + 0.5) * sx - 0.5;
		c.cy = (cam->cy + 0.5) * sy - 0.5;
		c.model = MVOD_CAM_PINHOLE_RADTAN;
		p->remap = mvod_camera_has_distortion(cam);
		if (p->remap)
			build_maps(p.get(), cam, K_of(&c));
		p->grey.create(p->in_h, p->in_w, CV_8UC1);
		p->scaled.create(p->out_h, p->out_w, CV_8UC1);
		p->blurred.create(p->out_h, p->out_w, CV_8UC1);
		*out_cam = c;
		*out = p.release();
		return 0;
	});
}

extern "C" int mvod_cv_preproc_run(struct mvod_cv_preproc *p, const struct mvod_image *in,
				   struct mvod_image *out)
{
	if (in->w != p->in_w || in->h != p->in_h)
		return -EINVAL;
	if (in->fmt != MVOD_PIX_GREY && in->fmt != MVOD_PIX_BGR)
		return -EINVAL;
	return mvod_guarded([&] {
		cv::Mat src = view(in);
		if (in->fmt == MVOD_PIX_BGR) {
			cv::cvtColor(src, p->grey, cv::COLOR_BGR2GRAY);
			src = p->grey;
		}
		cv::Mat *cur = &src;
		if (p->remap) {
			cv::remap(*cur, p->scaled, p->map1, p->map2, cv::INTER_LINEAR,
				  cv::BORDER_CONSTANT);
			cur = &p->scaled;
		} else if (p->out_w != p->in_w || p->out_h != p->in_h) {
			cv::resize(*cur, p->scaled, p->scaled.size(), 0, 0, cv::INTER_AREA);
			cur = &p->scaled;
		}
		if (p->blur_ksize > 1) {
			cv::GaussianBlur(*cur, p->blurred, cv::Size(p->blur_ksize, p->blur_ksize), 0);
			cur = &p->blurred;
		}
		*out = image_of(*cur);
		return 0;
	});
}

extern "C" void mvod_cv_preproc_destroy(struct mvod_cv_preproc *p)
{
	delete p;
}

struct mvod_cv_detector {
	cv::Ptr<cv::Feature2D> f2d;
	int desc_bytes, max_features;
	std::vector<cv::KeyPoint> kps;
	cv::Mat desc;
	cv::Ptr<cv::ORB> orb, band;   /* ORB only: f2d as ORB, and the road band's own detector */
	cv::Mat mask;                 /* width x height, 255 off the band (mvod_cv_detect_band) */
	cv::Mat band_mask;            /* its complement */
};

extern "C" int mvod_cv_desc_bytes(enum mvod_detector kind)
{
	return kind == MVOD_DETECTOR_SIFT ? MVOD_SIFT_DESC_BYTES : MVOD_ORB_DESC_BYTES;
}

extern "C" int mvod_cv_detector_create(enum mvod_detector kind, int max_features, int width,
				       int height, struct mvod_cv_detector **out)
{
	if (max_features < 8 || width < MVOD_VO_MIN_PX || height < MVOD_VO_MIN_PX)
		return -EINVAL;
	return mvod_guarded([&] {
		auto d = std::make_unique<mvod_cv_detector>();
		if (kind == MVOD_DETECTOR_SIFT) {
			d->f2d = cv::SIFT::create(max_features);
		} else {
			d->orb = cv::ORB::create(max_features);
			d->band = cv::ORB::create(max_features);
			d->f2d = d->orb;
			d->mask.create(height, width, CV_8U);
			d->band_mask.create(height, width, CV_8U);
		}
		d->desc_bytes = mvod_cv_desc_bytes(kind);
		d->max_features = max_features;
		d->kps.reserve((size_t)max_features * 2);
		/*
		 * Shaped as the detector returns a frame with max_features features (SIFT: rows of
		 * 128 CV_32F, ORB: 32 CV_8U), so that Mat::create keeps this buffer for such frames.
		 * Any other shape makes OpenCV allocate anew: SIFT keeps keypoints tied with the
		 * last one, 2001 of 2000 on 3 of 20 KITTI frames, and those frames still do.
		 */
		d->desc.create(max_features, d->f2d->descriptorSize(), d->f2d->descriptorType());
		*out = d.release();
		return 0;
	});
}

/* d->kps and d->desc appended to out, up to its cap. */
static void append(const struct mvod_cv_detector *d, struct mvod_features *out)
{
	int n = std::min((int)d->kps.size(), out->cap - out->n);
	for (int i = 0; i < n; i++) {
		struct mvod_keypoint *k = &out->kp[out->n + i];
		k->x = d->kps[(size_t)i].pt.x;
		k->y = d->kps[(size_t)i].pt.y;
		k->octave = d->kps[(size_t)i].octave;
		k->response = d->kps[(size_t)i].response;
		memcpy(out->desc + (size_t)(out->n + i) * d->desc_bytes, d->desc.ptr(i),
		       (size_t)d->desc_bytes);
	}
	out->n += n;
}

extern "C" int mvod_cv_detect(struct mvod_cv_detector *d, const struct mvod_image *grey,
			      struct mvod_features *out)
{
	if (grey->fmt != MVOD_PIX_GREY || out->desc_bytes != d->desc_bytes)
		return -EINVAL;
	return mvod_guarded([&] {
		if (d->orb)
			d->orb->setMaxFeatures(d->max_features);
		d->f2d->detectAndCompute(view(grey), cv::noArray(), d->kps, d->desc);
		out->n = 0;
		append(d, out);
		return 0;
	});
}

extern "C" int mvod_cv_detect_band(struct mvod_cv_detector *d, const struct mvod_image *grey,
				   const float quad[8], int band_features, int fast_threshold,
				   struct mvod_features *out)
{
	if (!d->orb)
		return mvod_cv_detect(d, grey, out);
	if (grey->fmt != MVOD_PIX_GREY || out->desc_bytes != d->desc_bytes ||
	    grey->w != d->mask.cols || grey->h != d->mask.rows || band_features < 1 ||
	    band_features >= d->max_features)
		return -EINVAL;
	return mvod_guarded([&] {
		cv::Point poly[4];
		for (int i = 0; i < 4; i++)
			poly[i] = cv::Point(cvRound(quad[2 * i]), cvRound(quad[2 * i + 1]));
		d->band_mask.setTo(0);
		cv::fillConvexPoly(d->band_mask, poly, 4, cv::Scalar(255));
		cv::bitwise_not(d->band_mask, d->mask);
		d->orb->setMaxFeatures(d->max_features - band_features);
		d->orb->detectAndCompute(view(grey), d->mask, d->kps, d->desc);
		out->n = 0;
		append(d, out);
		d->band->setMaxFeatures(band_features);
		d->band->setFastThreshold(fast_threshold);
		d->band->detectAndCompute(view(grey), d->band_mask, d->kps, d->desc);
		append(d, out);
		return 0;
	});
}

extern "C" void mvod_cv_detector_destroy(struct mvod_cv_detector *d)
{
	delete d;
}

struct mvod_cv_nn {
	cv::Ptr<cv::DescriptorMatcher> m;
	bool binary;
	std::vector<std::vector<cv::DMatch>> knn;
};

/*
 * The reference implementation's FLANN settings: LSH with 6 tables, 12-bit keys, probe level
 * 1 for binary descriptors; 5 kd-trees searched with 50 checks for SIFT.
 */
static cv::Ptr<cv::DescriptorMatcher> make_matcher(bool binary, bool flann)
{
	if (!flann)
		return cv::BFMatcher::create(binary ? cv::NORM_HAMMING : cv::NORM_L2);
	auto search = cv::makePtr<cv::flann::SearchParams>(50);
	if (binary)
		return cv::makePtr<cv::FlannBasedMatcher>(
			cv::makePtr<cv::flann::LshIndexParams>(6, 12, 1), search);
	return cv::makePtr<cv::FlannBasedMatcher>(cv::makePtr<cv::flann::KDTreeIndexParams>(5),
						  search);
}

extern "C" int mvod_cv_nn_create(enum mvod_detector kind, bool flann, struct mvod_cv_nn **out)
{
	return mvod_guarded([&] {
		auto nn = std::make_unique<mvod_cv_nn>();
		nn->binary = kind == MVOD_DETECTOR_ORB;
		nn->m = make_matcher(nn->binary, flann);
		*out = nn.release();
		return 0;
	});
}

static cv::Mat descriptors(const struct mvod_features *f, bool binary)
{
	if (binary)
		return cv::Mat(f->n, f->desc_bytes, CV_8U, f->desc);
	return cv::Mat(f->n, f->desc_bytes / (int)sizeof(float), CV_32F, f->desc);
}

extern "C" int mvod_cv_nn_search(struct mvod_cv_nn *nn, const struct mvod_features *a,
				 const struct mvod_features *b, float *best_a, float *second_a,
				 int *idx_a, int *idx_b)
{
	return mvod_guarded([&] {
		cv::Mat da = descriptors(a, nn->binary), db = descriptors(b, nn->binary);
		/* OpenCV appends to the result vector: it must start empty. */
		nn->knn.clear();
		nn->m->knnMatch(da, db, nn->knn, 2);
		for (int i = 0; i < a->n; i++) {
			const auto *k = (size_t)i < nn->knn.size() ? &nn->knn[(size_t)i] : nullptr;
			bool found = k && !k->empty();
			idx_a[i] = found ? (*k)[0].trainIdx : -1;
			best_a[i] = found ? (*k)[0].distance : HUGE_VALF;
			second_a[i] = found && k->size() > 1 ? (*k)[1].distance : best_a[i];
		}
		if (!idx_b)
			return 0;
		nn->knn.clear();
		nn->m->knnMatch(db, da, nn->knn, 1);
		for (int j = 0; j < b->n; j++) {
			const auto *k = (size_t)j < nn->knn.size() ? &nn->knn[(size_t)j] : nullptr;
			idx_b[j] = k && !k->empty() ? (*k)[0].trainIdx : -1;
		}
		return 0;
	});
}

extern "C" void mvod_cv_nn_destroy(struct mvod_cv_nn *nn)
{
	delete nn;
}

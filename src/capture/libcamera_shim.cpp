/*
 * libcamera 0.0.3 behind the C functions of libcamera_shim.h. libcamera completes requests on
 * its own thread: completed ones wait in a queue (at most one per buffer) for the capture
 * thread, which converts the frame and queues the request again.
 */
#include "capture/libcamera_shim.h"

#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <sys/mman.h>

#include <libcamera/libcamera.h>

#include "util/errbuf.h"
#include "util/shim_guard.hpp"

using namespace libcamera;

/* A buffer's planes mapped once, for the life of the camera. */
struct mapping {
	void *base = MAP_FAILED;
	size_t len = 0;
	const uint8_t *data = nullptr; /* plane 0 */
	size_t avail = 0;              /* bytes from plane 0 to the end of the last plane */
};

struct mvod_lcam {
	std::unique_ptr<CameraManager> cm;
	std::shared_ptr<Camera> cam;
	std::unique_ptr<CameraConfiguration> config;
	std::unique_ptr<FrameBufferAllocator> alloc;
	std::vector<std::unique_ptr<Request>> requests;
	std::vector<mapping> maps;
	Stream *stream = nullptr;
	bool acquired = false, started = false;
	std::mutex lock;
	std::condition_variable done;
	/*
	 * Completed requests in order, a ring sized once to the request count (each request is in
	 * it at most once): a std::deque would allocate and free blocks as frames flow.
	 */
	std::vector<Request *> completed;
	size_t head = 0, queued = 0;
	bool disconnected = false;
	Request *current = nullptr; /* handed to the caller, not yet released */

	void on_complete(Request *r)
	{
		if (r->status() == Request::RequestCancelled)
			return;
		std::lock_guard<std::mutex> g(lock);
		completed[(head + queued++) % completed.size()] = r;
		done.notify_one();
	}
	void on_disconnect()
	{
		std::lock_guard<std::mutex> g(lock);
		disconnected = true;
		done.notify_one();
	}
	~mvod_lcam()
	{
		if (started)
			cam->stop();
		for (auto &m : maps)
			if (m.base != MAP_FAILED)
				munmap(m.base, m.len);
		requests.clear();
		alloc.reset();
		if (acquired)
			cam->release();
		cam.reset();
		if (cm)
			cm->stop();
	}
};

static std::shared_ptr<Camera> find_camera(CameraManager &cm, const mvod_lcam_want *w)
{
	if (w->id[0])
		return cm.get(w->id);
	auto cams = cm.cameras();
	return w->index < (long)cams.size() ? cams[(size_t)w->index] : nullptr;
}

static int configure(mvod_lcam *c, const mvod_lcam_want *w, mvod_lcam_mode *mode, char *err,
		     size_t errlen)
{
	c->config = c->cam->generateConfiguration({StreamRole::Viewfinder});
	if (!c->config || c->config->empty())
		return mvod_errf(err, errlen, -EINVAL, "libcamera camera %s has no video stream",
				 c->cam->id().c_str());
	StreamConfiguration &sc = c->config->at(0);
	enum mvod_camfmt f = w->format >= 0 ? (enum mvod_camfmt)w->format : MVOD_CAMFMT_YUYV;
	sc.pixelFormat = PixelFormat(mvod_camfmt_fourcc(f, MVOD_CAMFMT_LIBCAMERA));
	if (w->width)
		sc.size.width = (unsigned)w->width;
	if (w->height)
		sc.size.height = (unsigned)w->height;
	Size asked = sc.size;
	if (c->config->validate() == CameraConfiguration::Invalid ||
	    mvod_camfmt_of_fourcc(sc.pixelFormat.fourcc(), MVOD_CAMFMT_LIBCAMERA, &mode->fmt) < 0 ||
	    (w->format >= 0 && mode->fmt != f) || sc.size != asked)
		return mvod_errf(err, errlen, -EINVAL, "libcamera camera %s cannot deliver %ux%u %s "
				 "(it offers %s): pick a mode from mvod --list-cameras",
				 c->cam->id().c_str(), asked.width, asked.height,
				 mvod_camfmt_name(f), sc.toString().c_str());
	if (c->cam->configure(c->config.get()) < 0)
		return mvod_errf(err, errlen, -EIO, "libcamera camera %s refused its configuration",
				 c->cam->id().c_str());
	c->stream = sc.stream();
	*mode = {(int)sc.size.width, (int)sc.size.height, (int)sc.stride, mode->fmt};
	return 0;
}

static int map_buffer(mvod_lcam *c, const FrameBuffer &b)
{
	mapping m;
	const auto &planes = b.planes();
	for (const auto &p : planes)
		if (p.fd.get() == planes[0].fd.get())
			m.len = std::max(m.len, (size_t)p.offset + p.length);
	m.base = mmap(nullptr, m.len, PROT_READ, MAP_SHARED, planes[0].fd.get(), 0);
	if (m.base == MAP_FAILED)
		return -errno;
	m.data = (const uint8_t *)m.base + planes[0].offset;
	m.avail = m.len - planes[0].offset;
	c->maps.push_back(m);
	return 0;
}

static int make_requests(mvod_lcam *c, char *err, size_t errlen)
{
	c->alloc = std::make_unique<FrameBufferAllocator>(c->cam);
	if (c->alloc->allocate(c->stream) < 2)
		return mvod_errf(err, errlen, -ENOMEM, "libcamera camera %s: fewer than 2 buffers",
				 c->cam->id().c_str());
	const auto &bufs = c->alloc->buffers(c->stream);
	for (size_t i = 0; i < bufs.size(); i++) {
		std::unique_ptr<Request> r = c->cam->createRequest(i);
		int ret = r ? r->addBuffer(c->stream, bufs[i].get()) : -ENOMEM;
		if (!ret)
			ret = map_buffer(c, *bufs[i]);
		if (ret)
			return mvod_errf(err, errlen, ret, "libcamera camera %s: cannot set up buffer "
					 "%zu: %s", c->cam->id().c_str(), i, strerror(-ret));
		c->requests.push_back(std::move(r));
	}
	c->completed.assign(c->requests.size(), nullptr);
	return 0;
}

static int start(mvod_lcam *c, char *err, size_t errlen)
{
	c->cam->requestCompleted.connect(c, &mvod_lcam::on_complete);
	c->cam->disconnected.connect(c, &mvod_lcam::on_disconnect);
	int ret = c->cam->start();
	c->started = ret == 0;
	for (size_t i = 0; !ret && i < c->requests.size(); i++)
		ret = c->cam->queueRequest(c->requests[i].get());
	if (ret)
		return mvod_errf(err, errlen, ret, "libcamera camera %s: cannot start: %s",
				 c->cam->id().c_str(), strerror(-ret));
	return 0;
}

static int open_camera(mvod_lcam *c, const mvod_lcam_want *w, mvod_lcam_mode *mode, char *err,
		       size_t errlen)
{
	c->cm = std::make_unique<CameraManager>();
	int ret = c->cm->start();
	if (ret) {
		c->cm.reset();
		return mvod_errf(err, errlen, ret, "libcamera cannot start: %s", strerror(-ret));
	}
	c->cam = find_camera(*c->cm, w);
	if (!c->cam && w->id[0])
		return mvod_errf(err, errlen, -ENODEV, "no libcamera camera \"%s\": mvod "
				 "--list-cameras shows the cameras there are", w->id);
	if (!c->cam)
		return mvod_errf(err, errlen, -ENODEV, "no libcamera camera %ld (%zu found): mvod "
				 "--list-cameras shows the cameras there are", w->index,
				 c->cm->cameras().size());
	if (c->cam->acquire() < 0)
		return mvod_errf(err, errlen, -EBUSY, "libcamera camera %s is busy: another program "
				 "is using it", c->cam->id().c_str());
	c->acquired = true;
	ret = configure(c, w, mode, err, errlen);
	if (!ret)
		ret = make_requests(c, err, errlen);
	return ret ? ret : start(c, err, errlen);
}

extern "C" int mvod_lcam_open(const struct mvod_lcam_want *want, struct mvod_lcam **out,
			      struct mvod_lcam_mode *mode, char *err, size_t errlen)
{
	mvod_lcam *opened = nullptr;
	int ret = mvod_guarded([&] {
		auto c = std::make_unique<mvod_lcam>();
		int r = open_camera(c.get(), want, mode, err, errlen);
		if (r == 0)
			opened = c.release();
		return r;
	});
	if (ret == 0)
		*out = opened;
	else if (err && errlen && !err[0])
		mvod_errf(err, errlen, ret, "libcamera failed: %s", strerror(-ret));
	return ret;
}

extern "C" int mvod_lcam_wait(struct mvod_lcam *c, int timeout_ms, struct mvod_lcam_frame *f)
{
	return mvod_guarded([&] {
		std::unique_lock<std::mutex> g(c->lock);
		c->done.wait_for(g, std::chrono::milliseconds(timeout_ms),
				 [&] { return c->disconnected || c->queued > 0; });
		if (c->disconnected)
			return -ENODEV;
		if (c->queued == 0)
			return -EAGAIN;
		Request *r = c->completed[c->head];
		c->head = (c->head + 1) % c->completed.size();
		c->queued--;
		g.unlock();
		c->current = r;
		const FrameBuffer *b = r->findBuffer(c->stream);
		const mapping &m = c->maps[r->cookie()];
		const FrameMetadata &md = b->metadata();
		size_t used = md.planes().empty() ? m.avail : md.planes()[0].bytesused;
		*f = {m.data, std::min(used, m.avail), md.sequence, (int64_t)(md.timestamp / 1000),
		      md.status != FrameMetadata::FrameSuccess};
		return 0;
	});
}

extern "C" int mvod_lcam_release(struct mvod_lcam *c)
{
	return mvod_guarded([&] {
		Request *r = c->current;
		c->current = nullptr;
		if (!r)
			return 0;
		r->reuse(Request::ReuseBuffers);
		return c->cam->queueRequest(r);
	});
}

extern "C" void mvod_lcam_close(struct mvod_lcam *c)
{
	(void)mvod_guarded([&] {
		delete c;
		return 0;
	});
}

extern "C" int mvod_lcam_list(FILE *out)
{
	int n = 0;
	(void)mvod_guarded([&] {
		CameraManager cm;
		if (cm.start() < 0)
			return -EIO;
		for (const auto &cam : cm.cameras()) {
			auto model = cam->properties().get(properties::Model);
			fprintf(out, "libcamera:%d  %s (%s)\n    --source 'libcamera:%d?width=640&"
				"height=480&format=YUYV'  (or libcamera:%s)\n", n,
				model ? model->c_str() : "unknown model", cam->id().c_str(), n,
				cam->id().c_str());
			n++;
		}
		cm.stop();
		return 0;
	});
	return n;
}

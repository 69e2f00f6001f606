/*
 * The per-frame loop of mvod's own code makes no heap allocation.
 *
 * malloc and its kin are defined here, forwarding to glibc's __libc_* entry points: the test
 * executable links libmvod statically, so these definitions win for every shared library too.
 * While counting is on, each call is charged to the first stack frame outside the C library
 * and the dynamic loader: a frame in this executable is mvod's own C code (the *_shim.cpp
 * objects allocate only through operator new in libstdc++ or cv::fastMalloc in OpenCV, both
 * shared libraries, so they are charged there); any other frame names the library that asked
 * (OpenCV, libstdc++, FFmpeg, LCM).
 *
 * The pipeline then runs the same clip twice, for SHORT and LONG frames, after a warm-up run
 * that takes the one-time costs (OpenCV's thread pool, FFmpeg's codec tables). Everything but
 * the per-frame loop is identical in the two runs, so LONG - SHORT counts the allocations of
 * LONG - SHORT frames in steady state: mvod's own must be zero. The whole count per frame,
 * OpenCV's included, is printed for the record, each library's with the mvod function the
 * unwinder found below it: a guide to which stage asks, not part of the assertion (FFmpeg's
 * frame threads and code without unwind tables can put a call under the wrong one).
 *
 * Map mode's bundle adjustment runs on its own thread, named "mvod-ba"
 * (src/vo/optim/ba_thread.c): everything that thread allocates is charged to it as a whole, and
 * asserted to be nothing per frame too (its solver, ba_lm.c, works on buffers made at create).
 */
#include <dlfcn.h>
#include <link.h>
#include <errno.h>
#include <malloc.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <unwind.h>

#include <cjson/cJSON.h>
#include <cmocka.h>

#include "harness.h"
#include "mvod/ipc.h"
#include "mvod/pipeline.h"

#define WARMUP 20
#define SHORT 50
#define LONG 250
#define OWNERS 32

/* AddressSanitizer owns malloc in its builds: interposing it there is neither possible nor needed. */
#if defined(__SANITIZE_ADDRESS__)
int main(void)
{
	return EXIT_SKIP;
}
#else

void *__libc_malloc(size_t size);
void *__libc_calloc(size_t n, size_t size);
void *__libc_realloc(void *p, size_t size);
void *__libc_memalign(size_t align, size_t size);
void __libc_free(void *p);

/* Who asked, by the object (executable or shared library) its code lies in. */
struct owner {
	const void *base;
	const char *name;
	const char *via; /* for a library: the mvod function that called into it, or "?" */
	atomic_long calls, bytes;
};

static struct owner owners[OWNERS];
static int n_owners;
static pthread_mutex_t owners_lock = PTHREAD_MUTEX_INITIALIZER;
static atomic_int counting;
static const void *exe_base, *libc_base;
static __thread int in_hook;

/* ISO C has no function-to-object pointer conversion; through an integer is defined on Linux. */
#define FN(f) ((const void *)(uintptr_t)(f))

/* The loaded object holding addr, or NULL. */
static const void *object_of(const void *addr, const char **name)
{
	Dl_info info;
	if (!dladdr(addr, &info))
		return NULL;
	if (name)
		*name = info.dli_fname;
	return info.dli_fbase;
}

/* The hooks' own frames are skipped by address range: section hooks holds only them. */
extern const char __start_alloc_hooks[], __stop_alloc_hooks[];
#define HOOK __attribute__((section("alloc_hooks"), noinline))

static bool is_hook(const void *pc)
{
	return (const char *)pc >= __start_alloc_hooks && (const char *)pc < __stop_alloc_hooks;
}

static struct owner *owner_for(const void *base, const char *name, const char *via)
{
	pthread_mutex_lock(&owners_lock);
	struct owner *o = NULL;
	for (int i = 0; i < n_owners && !o; i++)
		if (owners[i].base == base && owners[i].via == via)
			o = &owners[i];
	if (!o && n_owners < OWNERS) {
		o = &owners[n_owners++];
		o->base = base;
		o->name = name;
		o->via = via;
	}
	pthread_mutex_unlock(&owners_lock);
	return o;
}

/* The C and C++ runtimes allocate for whoever calls them: they are looked through. */
static bool plumbing(const void *base, const char *name)
{
	return base == libc_base || strstr(name, "/ld-linux") || strstr(name, "/libstdc++.so") ||
	       strstr(name, "/libgcc_s.so");
}

struct walk {
	const void *base;
	const char *name, *via;
};

/*
 * The exported mvod_* function holding pc in this executable, or NULL. dladdr names the
 * nearest symbol below pc even past its end (a lambda the shim's function calls has none of
 * its own): the symbol's size tells.
 */
static const char *mvod_function(const void *pc)
{
	Dl_info info;
	const ElfW(Sym) *sym = NULL;
	if (!dladdr1(pc, &info, (void **)&sym, RTLD_DL_SYMENT) || info.dli_fbase != exe_base ||
	    !info.dli_sname || !sym)
		return NULL;
	bool inside = (const char *)pc < (const char *)info.dli_saddr + sym->st_size;
	return inside && strncmp(info.dli_sname, "mvod_", 5) == 0 ? info.dli_sname : NULL;
}

/*
 * Finds the first frame that is neither a hook nor plumbing: the owner. For a library, walks
 * on to the mvod function that called into it (the tests export their symbols for dladdr).
 */
HOOK static _Unwind_Reason_Code visit(struct _Unwind_Context *ctx, void *arg)
{
	struct walk *w = arg;
	const void *pc = (const void *)_Unwind_GetIP(ctx);
	if (w->base) {
		w->via = mvod_function(pc);
		return w->via ? _URC_END_OF_STACK : _URC_NO_REASON;
	}
	if (is_hook(pc))
		return _URC_NO_REASON;
	const char *name = "?";
	const void *base = object_of(pc, &name);
	if (!base || plumbing(base, name))
		return _URC_NO_REASON;
	w->base = base;
	w->name = name;
	return base == exe_base ? _URC_END_OF_STACK : _URC_NO_REASON;
}

/* The owner standing for the whole bundle-adjustment thread. */
static const char ba_thread_owner = 0;

/* The calling thread is map mode's bundle adjustment (prctl reads its name without allocating). */
HOOK static bool on_ba_thread(void)
{
	char name[16] = "";
	prctl(PR_GET_NAME, name, 0, 0, 0);
	return strcmp(name, "mvod-ba") == 0;
}

HOOK static void charge(size_t size)
{
	if (!atomic_load(&counting) || in_hook)
		return;
	in_hook = 1;
	struct walk w = {NULL, "unknown", NULL};
	if (on_ba_thread())
		w = (struct walk){&ba_thread_owner, "mvod-ba thread", "(all of it)"};
	else
		_Unwind_Backtrace(visit, &w);
	struct owner *o = owner_for(w.base, w.name, w.via ? w.via : "?");
	if (o) {
		atomic_fetch_add(&o->calls, 1);
		atomic_fetch_add(&o->bytes, (long)size);
	}
	in_hook = 0;
}

HOOK void *malloc(size_t size)
{
	charge(size);
	return __libc_malloc(size);
}

HOOK void *calloc(size_t n, size_t size)
{
	charge(n * size);
	return __libc_calloc(n, size);
}

HOOK void *realloc(void *p, size_t size)
{
	charge(size);
	return __libc_realloc(p, size);
}

HOOK void *memalign(size_t align, size_t size)
{
	charge(size);
	return __libc_memalign(align, size);
}

HOOK void *aligned_alloc(size_t align, size_t size)
{
	return memalign(align, size);
}

HOOK int posix_memalign(void **p, size_t align, size_t size)
{
	*p = memalign(align, size);
	return *p ? 0 : ENOMEM;
}

/* Frees are not counted: every allocation the loop made would show up as a call above. */
void free(void *p)
{
	__libc_free(p);
}

struct tally {
	long calls[OWNERS], bytes[OWNERS];
};

static char dir[256];

static int setup(void **state)
{
	(void)state;
	snprintf(dir, sizeof(dir), "%s/seq", harness_tmpdir());
	/* turn: straight, a turn, straight again, so that tracking sees every kind of step. */
	harness_synth(dir, "turn", LONG, "mkv", "--size", "320x240", "--speed", "2", NULL);
	exe_base = object_of(FN(setup), NULL);
	libc_base = object_of(FN(__libc_malloc), NULL);
	return 0;
}

/* Runs the pipeline over max_frames frames of the clip, with every output on, under the count. */
static void run(int64_t max_frames, bool count, enum mvod_frontend fe, enum mvod_vo_mode mode,
		enum mvod_scale_mode scale, struct tally *t)
{
	char source[300], calib[300], traj[300], url[400];
	snprintf(source, sizeof(source), "file:%s/video.mkv", dir);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	snprintf(traj, sizeof(traj), "%s/out.tum", dir);
	snprintf(url, sizeof(url), "file://%s/out.lcmlog?mode=w", dir);
	struct mvod_ipc *ipc;
	assert_int_equal(mvod_ipc_create(url, NULL, NULL, &ipc), 0);
	struct mvod_run_opts o;
	mvod_run_opts_default(&o);
	o.source = source;
	o.calib = calib;
	o.trajectory = traj;
	o.max_frames = max_frames;
	o.vo.frontend = fe;
	o.vo.mode = mode;
	o.vo.scale_mode = scale;
	o.vo.camera_height_m = 1.6; /* mvod-synth's street: the ground 1.6 m below the camera */
	o.vo.ba_sync = true; /* the same keyframes land their bundle adjustment on every run */
	struct mvod_run_summary sum;
	for (int i = 0; i < n_owners; i++) {
		atomic_store(&owners[i].calls, 0);
		atomic_store(&owners[i].bytes, 0);
	}
	atomic_store(&counting, count);
	int ret = mvod_run(&o, ipc, NULL, &sum);
	atomic_store(&counting, 0);
	mvod_ipc_destroy(ipc);
	assert_int_equal(ret, 0);
	assert_int_equal(sum.frames, max_frames);
	for (int i = 0; i < OWNERS; i++) {
		t->calls[i] = i < n_owners ? atomic_load(&owners[i].calls) : 0;
		t->bytes[i] = i < n_owners ? atomic_load(&owners[i].bytes) : 0;
	}
}

static void loop_allocates_nothing_of_its_own(enum mvod_frontend fe, enum mvod_vo_mode mode,
					      enum mvod_scale_mode scale)
{
	struct tally warm, a, b;
	run(WARMUP, false, fe, mode, scale, &warm);
	run(SHORT, true, fe, mode, scale, &a);
	run(LONG, true, fe, mode, scale, &b);
	const double frames = LONG - SHORT;
	long own = -1, ba = 0, total_calls = 0, total_bytes = 0;
	printf("allocations per frame in steady state, by the object that asked, and through which "
	       "mvod function:\n");
	for (int i = 0; i < n_owners; i++) {
		long dc = b.calls[i] - a.calls[i], db = b.bytes[i] - a.bytes[i];
		bool mine = owners[i].base == exe_base;
		if (mine)
			own = dc;
		if (owners[i].base == &ba_thread_owner)
			ba = dc;
		total_calls += dc;
		total_bytes += db;
		const char *slash = strrchr(owners[i].name, '/');
		if (dc || mine)
			printf("  %-28s %-26s %8.2f calls %9.0f bytes\n",
			       mine ? "mvod's own code" : slash ? slash + 1 : owners[i].name,
			       mine ? "" : owners[i].via, dc / frames, db / frames);
	}
	printf("  %-55s %8.2f calls %9.0f bytes\n", "total", total_calls / frames,
	       total_bytes / frames);
	/* mvod allocates at setup, so it has an entry; its per-frame difference must be none. */
	assert_int_equal(own, 0);
	assert_int_equal(ba, 0);
}

static void test_loop_allocates_nothing_of_its_own(void **state)
{
	(void)state;
	loop_allocates_nothing_of_its_own(MVOD_FRONTEND_ORB, MVOD_VO_TWOVIEW,
					  MVOD_SCALE_MODE_AUTO);
}

/*
 * Map mode: tracking, keyframes, triangulation and the window's snapshot on the frame thread
 * use buffers made at create, as bundle adjustment on its thread does (see the top).
 */
static void test_map_loop_allocates_nothing_of_its_own(void **state)
{
	(void)state;
	loop_allocates_nothing_of_its_own(MVOD_FRONTEND_ORB, MVOD_VO_MAP,
					  MVOD_SCALE_MODE_AUTO);
}

/* Map mode on KLT tracks (auto's choice): the point ids ride in the tracks' fixed arrays. */
static void test_map_klt_loop_allocates_nothing_of_its_own(void **state)
{
	(void)state;
	loop_allocates_nothing_of_its_own(MVOD_FRONTEND_KLT, MVOD_VO_MAP,
					  MVOD_SCALE_MODE_AUTO);
}

/*
 * Map mode on KLT tracks with the camera's height: the road band's fit, the map's rescaling
 * and the keyframe rule a given scale adds (the baseline over the tracks' median depth).
 */
static void test_map_klt_height_loop_allocates_nothing_of_its_own(void **state)
{
	(void)state;
	loop_allocates_nothing_of_its_own(MVOD_FRONTEND_KLT, MVOD_VO_MAP, MVOD_SCALE_MODE_HEIGHT);
}

/* The KLT front end's tracks, corners and pyramids live in buffers made at create. */
static void test_klt_loop_allocates_nothing_of_its_own(void **state)
{
	(void)state;
	loop_allocates_nothing_of_its_own(MVOD_FRONTEND_KLT, MVOD_VO_TWOVIEW,
					  MVOD_SCALE_MODE_AUTO);
}

static long calls_of(const void *base)
{
	long n = 0;
	for (int i = 0; i < n_owners; i++)
		if (owners[i].base == base)
			n += atomic_load(&owners[i].calls);
	return n;
}

/*
 * The attribution itself: strdup allocates inside libc but is charged to this executable,
 * which called it; cJSON allocates in its own shared library and is charged there.
 */
static void test_attribution(void **state)
{
	(void)state;
	for (int i = 0; i < n_owners; i++)
		atomic_store(&owners[i].calls, 0);
	atomic_store(&counting, 1);
	char *volatile s = strdup("x");
	cJSON *volatile j = cJSON_CreateObject();
	atomic_store(&counting, 0);
	free(s);
	cJSON_Delete(j);
	assert_int_equal(calls_of(exe_base), 1);
	assert_int_equal(calls_of(object_of(FN(cJSON_CreateObject), NULL)), 1);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_attribution),
		cmocka_unit_test(test_loop_allocates_nothing_of_its_own),
		cmocka_unit_test(test_klt_loop_allocates_nothing_of_its_own),
		cmocka_unit_test(test_map_loop_allocates_nothing_of_its_own),
		cmocka_unit_test(test_map_klt_loop_allocates_nothing_of_its_own),
		cmocka_unit_test(test_map_klt_height_loop_allocates_nothing_of_its_own),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
#endif

/*
 * Copyright 2026 py_vision contributors
 *
 * Licensed under the Apache License, Version 2.0 (the "License");
 * you may not use this file except in compliance with the License.
 * You may obtain a copy of the License at
 *
 *     http://www.apache.org/licenses/LICENSE-2.0
 *
 * Unless required by applicable law or agreed to in writing, software
 * distributed under the License is distributed on an "AS IS" BASIS,
 * WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 * See the License for the specific language governing permissions and
 * limitations under the License.
 */

/*
 * An emulated UVC camera at the system-call level, loaded with LD_PRELOAD.
 *
 * Every camera named in PY_VISION_UVC_CAMERAS (directories separated by ':') answers at
 * /dev/videoN and its /dev/v4l/by-id and by-path links as Linux's uvcvideo driver does:
 * open, stat, readlink and realpath see a character device and two symbolic links; ioctl
 * answers the V4L2 API (capabilities, formats, sizes, intervals, controls, mmap streaming);
 * poll and select wait for frames. A camera directory holds camera.conf (what the camera
 * offers, written by the Python harness, emulated_camera.py) and state (a small file mapped
 * shared by every process using the camera: plugged or not, its node number, faults, the
 * streaming owner, the format and the control values), and served (a ring, mapped shared too,
 * of the JPEGs dequeued: index, length, CRC-32). Everything else goes to libc as is.
 *
 * An open emulated device is a real eventfd: its number is a real descriptor, and it is
 * readable exactly when poll on a V4L2 device would return: a filled buffer waits, the queue
 * is not streaming, or the camera is gone. A thread per streaming handle produces frames at
 * the negotiated interval.
 */

#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/select.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/types.h>
#include <sys/utsname.h>
#include <time.h>
#include <unistd.h>
#include <math.h>
#include <stddef.h>

#define EXPORT __attribute__((visibility("default")))

#define MAX_CAMERAS 8
#define MAX_FORMATS 24
#define MAX_PLANES 3
#define MAX_FRAMES 24
#define MAX_INTERVALS 12
#define MAX_CONTROLS 48
#define MAX_MENU 8
#define MAX_BUFFERS 32
#define MAX_FDS 4096
#define STATE_MAGIC 0x45435655u /* "UVCE" */
#define SERVED_SLOTS 4096        /* the served ring: a frame's record is at index % slots */
#define SERVED_CORRUPT 1u        /* a served record's flag: broken on purpose (corrupt_jpeg) */

/* The shared state file: offsets are the harness's (emulated_camera.py) too. */
struct shared_state {
    uint32_t magic;          /* 0 */
    int32_t node;            /* 4: the N of /dev/videoN */
    uint32_t plugged;        /* 8 */
    uint32_t generation;     /* 12: +1 at every unplug: older handles are dead */
    uint32_t stalled;        /* 16 */
    uint32_t denied;         /* 20 */
    uint64_t owner;          /* 24: the handle streaming (pid << 42 | instance << 16 | token) */
    uint32_t cur_format;     /* 32 */
    uint32_t cur_frame;      /* 36 */
    uint32_t cur_interval;   /* 40 */
    uint32_t reserved;       /* 44 */
    uint64_t sensor_frames;  /* 48: index of the next frame the sensor makes */
    uint64_t frames_served;  /* 56: frames delivered into buffers */
    int32_t values[64];      /* 64: control values, in camera.conf order (a button: presses) */
    uint64_t render_ns;      /* 320: CPU time spent making frames (all processes) */
    int64_t wide[64];        /* 328: the values of 64-bit controls, at the same index */
};

/* One JPEG handed to a DQBUF, in the served file; the harness reads it (served_jpegs). The
 * writer clears `tag`, fills the record, then sets `tag` to index + 1: a reader that sees the
 * same tag before and after reading the fields has a whole record. */
struct served_record {
    uint64_t tag;            /* 0: index + 1, 0 while empty or being written */
    uint32_t length;         /* 8: bytesused */
    uint32_t flags;          /* 12: SERVED_CORRUPT */
    uint32_t crc;            /* 16: CRC-32 (zlib's) of the bytes */
    uint32_t reserved;       /* 20 */
};

struct frame_desc {
    uint32_t width, height, sizeimage, bytesperline;
    uint32_t code_x, code_y, cell;        /* the frame-index code, cell 0: none */
    char background[PATH_MAX];            /* YUYV background of this size, or the picture in
                                             the format with every code cell black */
    char white[PATH_MAX];                 /* the same with every code cell white (raw) */
    uint32_t n_intervals;
    struct v4l2_fract intervals[MAX_INTERVALS];
};

/* A raw format's plane: `across` bytes for every `per` pixels of a row, a row every `down`
 * rows of the picture (py_vision.capture.pixel_formats.Plane). */
struct plane_desc {
    uint32_t across, per, down;
};

/* The USB 2.0 bus the cameras of one state directory share (the file `usb_bus` there, mapped
 * by every process): each streaming camera's isochronous reservation, in bytes per 125 us
 * microframe, as uvcvideo reserves it at STREAMON (an alternate setting of the camera's
 * endpoint); the host controller grants periodic transfers at most BUS_CAPACITY of the 7500
 * bytes a microframe carries (80 %), and refuses more with ENOSPC. */
#define BUS_SLOTS 16
#define BUS_CAPACITY 6000
struct bus_slot {
    uint64_t key;            /* the camera (its bus_key), 0: free */
    uint64_t owner;          /* the streaming handle (a dead process's reservation is void) */
    uint32_t bytes;
    uint32_t reserved;
};
struct bus_state {
    uint32_t lock;           /* 0: a spin lock, the mapping being shared across processes */
    uint32_t reserved;
    struct bus_slot slots[BUS_SLOTS];
};

/* A recorded clip a compressed video format (H.264) serves: its access units, each from its
 * start code and access unit delimiter (00 00 00 01 09) to the next one's, frame i of the
 * sensor unit i % n_units. */
struct clip {
    uint8_t *data;
    size_t len;
    uint32_t n_units;
    uint32_t *offset, *length;
};

struct format_desc {
    uint32_t fourcc, flags;
    char description[32];
    char clip_path[PATH_MAX];              /* a video format's clip file ("" for the others) */
    size_t clip_size;                      /* its length in bytes */
    struct clip clip;                      /* loaded from it at the first frame */
    uint32_t n_planes;                     /* 0: YUYV or JPEG, made from the YUYV picture */
    struct plane_desc planes[MAX_PLANES];
    uint32_t n_frames;
    struct frame_desc frames[MAX_FRAMES];
};

struct menu_entry {
    int32_t index;
    char name[32];
    int64_t value;                         /* an integer menu's entry */
};

struct control_desc {
    uint32_t id, type;
    int64_t minimum, maximum, step, def;
    uint32_t flags;
    uint32_t master_id;
    int32_t master_manual;
    char name[32];
    uint32_t n_menu;
    struct menu_entry menu[MAX_MENU];
    uint32_t elem_size, n_dims, dims[4];   /* an array's dimensions (n_dims 0: one value) */
    int effect;                            /* what the control does to the picture */
};

enum { FX_NONE, FX_BRIGHTNESS, FX_CONTRAST, FX_SATURATION, FX_GAIN, FX_EXPOSURE,
       FX_WHITE_BALANCE };
static const char *const effect_names[] = {"none", "brightness", "contrast", "saturation",
                                           "gain", "exposure", "white_balance"};

struct jpeg_cache;

struct camera {
    char dir[PATH_MAX];
    char driver[16];                       /* QUERYCAP's driver: uvcvideo unless told */
    struct bus_state *bus;                 /* its USB bus (NULL: not on one) */
    uint64_t bus_key;
    uint32_t compressed_payload;           /* bytes per microframe a compressed stream asks */
    uint32_t n_alts;                       /* the endpoint's alternate settings, ascending */
    uint32_t alts[16];
    char card[32];
    char bus_info[32];
    char by_id[PATH_MAX];
    char by_path[PATH_MAX];
    uint32_t n_formats;
    struct format_desc formats[MAX_FORMATS];
    uint32_t n_controls;
    struct control_desc controls[MAX_CONTROLS];
    uint32_t corrupt_every;
    int corrupt_mode;                      /* 0 truncate, 1 garbage, 2 no EOI, 3 cycle */
    uint32_t drop_every;                   /* every n-th frame lost on the way (no buffer) */
    uint32_t error_every;                  /* every n-th buffer flagged V4L2_BUF_FLAG_ERROR */
    int streamon_errno;                    /* what VIDIOC_STREAMON fails with (0: it works) */
    int no_userptr;                        /* 1: REQBUFS refuses V4L2_MEMORY_USERPTR (EINVAL),
                                              2: QBUF refuses its memory (EFAULT) */
    struct shared_state *state;
    struct served_record *served;          /* SERVED_SLOTS, or NULL: no served file */
    /* JPEG */
    uint8_t tables[2048];                  /* DQT and DHT segments from the harness */
    uint32_t tables_len;
    uint16_t quant[2][64];                 /* natural order */
    uint16_t huff_code[4][256];            /* DC0, AC0, DC1, AC1 */
    uint8_t huff_size[4][256];
    int have_tables;
    struct jpeg_cache *jcache[MAX_FORMATS][MAX_FRAMES];
    uint8_t *backgrounds[MAX_FRAMES * MAX_FORMATS];
    uint8_t *whites[MAX_FRAMES * MAX_FORMATS];    /* a raw format's picture, cells white */
    uint8_t *looks[MAX_FRAMES * MAX_FORMATS];     /* the backgrounds as the controls make them */
    uint64_t look_keys[MAX_FRAMES * MAX_FORMATS];
    pthread_mutex_t lock;                  /* backgrounds and JPEG caches */
};

enum { BUF_IDLE, BUF_QUEUED, BUF_DONE };

struct buffer {
    int state;
    uint32_t bytesused, sequence;
    struct timeval timestamp;
    int bg_frame;                          /* which background the buffer holds (YUYV) */
    uint64_t bg_look;                      /* and with which control values */
    int jpeg;                              /* holds a JPEG: record it when dequeued */
    int error;                             /* flagged V4L2_BUF_FLAG_ERROR */
    uint32_t crc, flags;                   /* its CRC-32 and SERVED_CORRUPT */
    uint64_t index;                        /* the sensor's index of the frame */
    uint8_t *user;                         /* USERPTR: the program's memory, as queued */
    size_t user_length;
};

struct handle {
    int fd;                                /* the descriptor it was opened as (the eventfd) */
    int refs;                              /* descriptors sharing it (dup, fcntl F_DUPFD) */
    int efd;                               /* our own duplicate of the eventfd */
    ino_t ino;
    struct camera *cam;
    uint32_t generation;
    uint64_t owner_id;
    int forked;
    int nonblock;                          /* opened with O_NONBLOCK */
    uint32_t in_flight;                    /* buffers the producer is filling */
    pthread_mutex_t lock;
    pthread_cond_t cond;
    int event_set;
    /* buffers */
    uint32_t n_buffers;
    size_t stride;
    int memfd;
    uint8_t *mem;
    uint32_t memory;                       /* V4L2_MEMORY_MMAP or V4L2_MEMORY_USERPTR */
    struct buffer buffers[MAX_BUFFERS];
    uint32_t queued[MAX_BUFFERS], n_queued;
    uint32_t done[MAX_BUFFERS], n_done;
    /* streaming */
    int streaming, stop, dead;
    pthread_t thread;
    uint32_t fmt, frame;
    struct v4l2_fract interval;
    uint32_t sequence;
    uint8_t *scratch;                      /* YUYV of the current frame, MJPEG mode */
    uint64_t scratch_look;
};

static struct camera *cameras[MAX_CAMERAS];
static int n_cameras;
static struct handle *handles[MAX_FDS];
static pthread_mutex_t table_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_once_t init_once = PTHREAD_ONCE_INIT;
static uint64_t instance_id;
static uint32_t next_token;
static uint32_t kernel_version;
static pid_t table_pid;    /* the process the handle table belongs to (not a vfork child) */

static int (*real_open)(const char *, int, ...);
static int (*real_open64)(const char *, int, ...);
static int (*real_openat)(int, const char *, int, ...);
static int (*real_openat64)(int, const char *, int, ...);
static int (*real_close)(int);
static int (*real_fcntl)(int, int, ...);
static int (*real_dup)(int);
static int (*real_dup2)(int, int);
static int (*real_dup3)(int, int, int);
static int (*real_ioctl)(int, unsigned long, ...);
static void *(*real_mmap)(void *, size_t, int, int, int, off_t);
static void *(*real_mmap64)(void *, size_t, int, int, int, off64_t);
static int (*real_poll)(struct pollfd *, nfds_t, int);
static int (*real_ppoll)(struct pollfd *, nfds_t, const struct timespec *, const sigset_t *);
static ssize_t (*real_read)(int, void *, size_t);
static int (*real_stat)(const char *, struct stat *);
static int (*real_lstat)(const char *, struct stat *);
static int (*real_fstat)(int, struct stat *);
static int (*real_fstatat)(int, const char *, struct stat *, int);
static int (*real_xstat)(int, const char *, struct stat *);
static int (*real_lxstat)(int, const char *, struct stat *);
static int (*real_fxstat)(int, int, struct stat *);
static int (*real_fxstatat)(int, int, const char *, struct stat *, int);
static int (*real_statx)(int, const char *, int, unsigned int, struct statx *);
static int (*real_access)(const char *, int);
static int (*real_faccessat)(int, const char *, int, int);
static ssize_t (*real_readlink)(const char *, char *, size_t);
static ssize_t (*real_readlinkat)(int, const char *, char *, size_t);
static char *(*real_realpath)(const char *, char *);
static DIR *(*real_opendir)(const char *);
static struct dirent *(*real_readdir)(DIR *);
static struct dirent64 *(*real_readdir64)(DIR *);
static int (*real_closedir)(DIR *);

/* ------------------------------------------------------------------ set-up */

static void *next_symbol(const char *name)
{
    return dlsym(RTLD_NEXT, name);
}

static void trim(char *s)
{
    size_t n = strlen(s);
    while (n && (s[n - 1] == '\n' || s[n - 1] == '\r' || s[n - 1] == ' '))
        s[--n] = 0;
}

static void copy_text(char *dst, size_t size, const char *src)
{
    snprintf(dst, size, "%s", src ? src : "");
}

static int parse_tables(struct camera *cam, const char *path);

static int fd_open_real(const char *path, int flags)
{
    return real_open ? real_open(path, flags) : -1;
}

static int read_file(const char *path, uint8_t *buf, size_t cap, size_t *len)
{
    int fd = fd_open_real(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return -1;
    size_t got = 0;
    while (got < cap) {
        ssize_t r = real_read(fd, buf + got, cap - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        got += (size_t)r;
    }
    real_close(fd);
    *len = got;
    return 0;
}

static void load_camera(const char *dir)
{
    char path[PATH_MAX + 32], line[1024];
    if (n_cameras >= MAX_CAMERAS)
        return;
    snprintf(path, sizeof(path), "%s/camera.conf", dir);
    int fd = fd_open_real(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return;
    FILE *f = fdopen(fd, "r");
    if (!f) {
        real_close(fd);
        return;
    }
    struct camera *cam = calloc(1, sizeof(*cam));
    if (!cam) {
        fclose(f);
        return;
    }
    copy_text(cam->dir, sizeof(cam->dir), dir);
    pthread_mutex_init(&cam->lock, NULL);
    struct format_desc *fmt = NULL;
    struct frame_desc *frm = NULL;
    while (fgets(line, sizeof(line), f)) {
        trim(line);
        char *rest = strchr(line, ' ');
        if (!rest)
            continue;
        *rest++ = 0;
        if (!strcmp(line, "card")) {
            copy_text(cam->card, sizeof(cam->card), rest);
        } else if (!strcmp(line, "driver")) {
            copy_text(cam->driver, sizeof(cam->driver), rest);
        } else if (!strcmp(line, "bus")) {
            unsigned long long key = 0;
            int n = 0;
            if (sscanf(rest, "%llu %u %n", &key, &cam->compressed_payload, &n) == 2) {
                cam->bus_key = key;
                int fd2 = fd_open_real(rest + n, O_RDWR | O_CLOEXEC);
                if (fd2 >= 0) {
                    void *p = real_mmap(NULL, 4096, PROT_READ | PROT_WRITE, MAP_SHARED, fd2, 0);
                    real_close(fd2);
                    cam->bus = p == MAP_FAILED ? NULL : p;
                }
            }
        } else if (!strcmp(line, "alts")) {
            int n = 0, used = 0;
            while (cam->n_alts < 16
                   && sscanf(rest + used, "%u %n", &cam->alts[cam->n_alts], &n) == 1) {
                cam->n_alts++;
                used += n;
            }
        } else if (!strcmp(line, "bus_info")) {
            copy_text(cam->bus_info, sizeof(cam->bus_info), rest);
        } else if (!strcmp(line, "by_id")) {
            copy_text(cam->by_id, sizeof(cam->by_id), rest);
        } else if (!strcmp(line, "by_path")) {
            copy_text(cam->by_path, sizeof(cam->by_path), rest);
        } else if (!strcmp(line, "jpeg_tables")) {
            cam->have_tables = parse_tables(cam, rest) == 0;
        } else if (!strcmp(line, "corrupt_every")) {
            cam->corrupt_every = (uint32_t)strtoul(rest, NULL, 10);
        } else if (!strcmp(line, "drop_every")) {
            cam->drop_every = (uint32_t)strtoul(rest, NULL, 10);
        } else if (!strcmp(line, "error_every")) {
            cam->error_every = (uint32_t)strtoul(rest, NULL, 10);
        } else if (!strcmp(line, "no_userptr")) {
            cam->no_userptr = (int)strtol(rest, NULL, 10);
        } else if (!strcmp(line, "streamon_errno")) {
            cam->streamon_errno = (int)strtol(rest, NULL, 10);
        } else if (!strcmp(line, "planes") && fmt) {
            int n = 0, used = 0;
            struct plane_desc *pl = fmt->planes;
            while (fmt->n_planes < MAX_PLANES
                   && sscanf(rest + used, "%u %u %u %n", &pl[fmt->n_planes].across,
                             &pl[fmt->n_planes].per, &pl[fmt->n_planes].down, &n) == 3) {
                fmt->n_planes++;
                used += n;
            }
        } else if (!strcmp(line, "clip") && fmt) {
            int n = 0;
            unsigned long size = 0;
            if (sscanf(rest, "%lu %n", &size, &n) == 1) {
                fmt->clip_size = size;
                copy_text(fmt->clip_path, sizeof(fmt->clip_path), rest + n);
            }
        } else if (!strcmp(line, "white") && frm) {
            copy_text(frm->white, sizeof(frm->white), rest);
        } else if (!strcmp(line, "corrupt_mode")) {
            cam->corrupt_mode = !strcmp(rest, "garbage") ? 1 : !strcmp(rest, "no_eoi") ? 2
                : !strcmp(rest, "cycle") ? 3 : 0;
        } else if (!strcmp(line, "format") && cam->n_formats < MAX_FORMATS) {
            fmt = &cam->formats[cam->n_formats++];
            frm = NULL;
            char four[8] = {0};
            int n = 0;
            if (sscanf(rest, "%4s %u %n", four, &fmt->flags, &n) >= 2) {
                for (size_t k = strlen(four); k < 4; k++)
                    four[k] = ' ';   /* 'Y16' is V4L2's 'Y16 ' */
                fmt->fourcc = v4l2_fourcc(four[0], four[1], four[2], four[3]);
                copy_text(fmt->description, sizeof(fmt->description), rest + n);
            }
        } else if (!strcmp(line, "frame") && fmt && fmt->n_frames < MAX_FRAMES) {
            frm = &fmt->frames[fmt->n_frames++];
            int n = 0;
            sscanf(rest, "%u %u %u %u %u %u %u %n", &frm->width, &frm->height, &frm->sizeimage,
                   &frm->bytesperline, &frm->code_x, &frm->code_y, &frm->cell, &n);
            copy_text(frm->background, sizeof(frm->background), rest + n);
        } else if (!strcmp(line, "interval") && frm && frm->n_intervals < MAX_INTERVALS) {
            struct v4l2_fract *iv = &frm->intervals[frm->n_intervals++];
            sscanf(rest, "%u %u", &iv->numerator, &iv->denominator);
        } else if (!strcmp(line, "control") && cam->n_controls < MAX_CONTROLS) {
            struct control_desc *c = &cam->controls[cam->n_controls++];
            int n = 0;
            long long lo = 0, hi = 0, step = 0, def = 0;
            sscanf(rest, "%i %u %lli %lli %lli %lli %u %i %d %u %n", (int *)&c->id, &c->type,
                   &lo, &hi, &step, &def, &c->flags, (int *)&c->master_id, &c->master_manual,
                   &c->elem_size, &n);
            c->minimum = lo;
            c->maximum = hi;
            c->step = step;
            c->def = def;
            copy_text(c->name, sizeof(c->name), rest + n);
            /* what the kernel's controls framework adds to every such control */
            if (c->type == V4L2_CTRL_TYPE_BUTTON)
                c->flags |= V4L2_CTRL_FLAG_WRITE_ONLY | V4L2_CTRL_FLAG_EXECUTE_ON_WRITE;
            if (c->type == V4L2_CTRL_TYPE_STRING || c->type >= V4L2_CTRL_COMPOUND_TYPES)
                c->flags |= V4L2_CTRL_FLAG_HAS_PAYLOAD;
        } else if (!strcmp(line, "dims")) {
            uint32_t id, d[4] = {0};
            int got = sscanf(rest, "%i %u %u %u %u", (int *)&id, &d[0], &d[1], &d[2], &d[3]);
            for (uint32_t i = 0; got > 1 && i < cam->n_controls; i++)
                if (cam->controls[i].id == id) {
                    cam->controls[i].n_dims = (uint32_t)(got - 1);
                    memcpy(cam->controls[i].dims, d, sizeof(d));
                    cam->controls[i].flags |= V4L2_CTRL_FLAG_HAS_PAYLOAD;
                }
        } else if (!strcmp(line, "effect")) {
            uint32_t id;
            char kind[32] = {0};
            if (sscanf(rest, "%i %31s", (int *)&id, kind) == 2)
                for (uint32_t i = 0; i < cam->n_controls; i++)
                    for (int k = 1; k < (int)(sizeof(effect_names) / sizeof(*effect_names)); k++)
                        if (cam->controls[i].id == id && !strcmp(kind, effect_names[k]))
                            cam->controls[i].effect = k;
        } else if (!strcmp(line, "menu")) {
            uint32_t id;
            int index, n = 0;
            if (sscanf(rest, "%i %d %n", (int *)&id, &index, &n) >= 2) {
                for (uint32_t i = 0; i < cam->n_controls; i++) {
                    struct control_desc *c = &cam->controls[i];
                    if (c->id == id && c->n_menu < MAX_MENU) {
                        c->menu[c->n_menu].index = index;
                        copy_text(c->menu[c->n_menu].name, 32, rest + n);
                        c->menu[c->n_menu].value = strtoll(rest + n, NULL, 0);
                        c->n_menu++;
                    }
                }
            }
        }
    }
    fclose(f);
    snprintf(path, sizeof(path), "%s/state", dir);
    fd = fd_open_real(path, O_RDWR | O_CLOEXEC);
    if (fd >= 0) {
        void *p = real_mmap(NULL, 4096, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
        real_close(fd);
        if (p != MAP_FAILED && ((struct shared_state *)p)->magic == STATE_MAGIC)
            cam->state = p;
    }
    if (!cam->state || !cam->n_formats) {
        free(cam);
        return;
    }
    size_t served_size = SERVED_SLOTS * sizeof(struct served_record);
    snprintf(path, sizeof(path), "%s/served", dir);
    fd = fd_open_real(path, O_RDWR | O_CLOEXEC);
    if (fd >= 0) {
        if (lseek(fd, 0, SEEK_END) >= (off_t)served_size) {
            void *p = real_mmap(NULL, served_size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
            if (p != MAP_FAILED)
                cam->served = p;
        }
        real_close(fd);
    }
    cameras[n_cameras++] = cam;
}

static void after_fork_child(void)
{
    table_pid = getpid();
    pthread_mutex_init(&table_lock, NULL);
    for (int i = 0; i < MAX_FDS; i++) {
        struct handle *h = handles[i];
        if (!h)
            continue;
        h->forked = 1;     /* the producer thread stayed in the parent */
        pthread_mutex_init(&h->lock, NULL);
        pthread_cond_init(&h->cond, NULL);
    }
    for (int i = 0; i < n_cameras; i++)
        pthread_mutex_init(&cameras[i]->lock, NULL);
}

static void init(void)
{
    real_open = next_symbol("open");
    real_open64 = next_symbol("open64");
    real_openat = next_symbol("openat");
    real_openat64 = next_symbol("openat64");
    real_close = next_symbol("close");
    real_fcntl = next_symbol("fcntl");
    real_dup = next_symbol("dup");
    real_dup2 = next_symbol("dup2");
    real_dup3 = next_symbol("dup3");
    real_ioctl = next_symbol("ioctl");
    real_mmap = next_symbol("mmap");
    real_mmap64 = next_symbol("mmap64");
    real_poll = next_symbol("poll");
    real_ppoll = next_symbol("ppoll");
    real_read = next_symbol("read");
    real_stat = next_symbol("stat");
    real_lstat = next_symbol("lstat");
    real_fstat = next_symbol("fstat");
    real_fstatat = next_symbol("fstatat");
    real_xstat = next_symbol("__xstat");
    real_lxstat = next_symbol("__lxstat");
    real_fxstat = next_symbol("__fxstat");
    real_fxstatat = next_symbol("__fxstatat");
    real_statx = next_symbol("statx");
    real_access = next_symbol("access");
    real_faccessat = next_symbol("faccessat");
    real_readlink = next_symbol("readlink");
    real_readlinkat = next_symbol("readlinkat");
    real_realpath = next_symbol("realpath");
    real_opendir = next_symbol("opendir");
    real_readdir = next_symbol("readdir");
    real_readdir64 = next_symbol("readdir64");
    real_closedir = next_symbol("closedir");
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    instance_id = ((uint64_t)ts.tv_nsec ^ ((uint64_t)ts.tv_sec << 20)) & 0x3FFFFFF;
    struct utsname u;
    unsigned a = 6, b = 0, c = 0;
    if (uname(&u) == 0)
        sscanf(u.release, "%u.%u.%u", &a, &b, &c);
    kernel_version = (a << 16) | (b << 8) | (c > 255 ? 255 : c);
    const char *list = getenv("PY_VISION_UVC_CAMERAS");
    if (list && *list) {
        char *copy = strdup(list), *save = NULL;
        for (char *dir = strtok_r(copy, ":", &save); dir; dir = strtok_r(NULL, ":", &save))
            load_camera(dir);
        free(copy);
    }
    table_pid = getpid();
    pthread_atfork(NULL, NULL, after_fork_child);
}

/* A vfork child (subprocess closing descriptors before exec) shares our memory but runs no
 * fork handlers: it must leave the table alone. */
static int table_is_ours(void)
{
    return getpid() == table_pid;
}

static void ensure_init(void)
{
    pthread_once(&init_once, init);
}

__attribute__((constructor)) static void on_load(void)
{
    ensure_init();
}

/* ------------------------------------------------------------------ paths */

enum { PATH_NONE, PATH_DEVICE, PATH_LINK, PATH_DIR };

static int plugged(struct camera *cam)
{
    return __atomic_load_n(&cam->state->plugged, __ATOMIC_ACQUIRE) != 0;
}

static int device_path(struct camera *cam, char *buf, size_t size)
{
    return snprintf(buf, size, "/dev/video%d",
                    __atomic_load_n(&cam->state->node, __ATOMIC_ACQUIRE));
}

/* The directories udev makes for the links: 1 /dev/v4l, 2 by-id, 3 by-path, else 0. */
static int link_dir(const char *path)
{
    char buf[64];
    size_t n = strlen(path);
    if (n >= sizeof(buf))
        return 0;
    memcpy(buf, path, n + 1);
    while (n > 1 && buf[n - 1] == '/')
        buf[--n] = 0;
    return !strcmp(buf, "/dev/v4l") ? 1 : !strcmp(buf, "/dev/v4l/by-id") ? 2
        : !strcmp(buf, "/dev/v4l/by-path") ? 3 : 0;
}

/* Which emulated file a path names (only while its camera is plugged). */
static int match_path(const char *path, struct camera **out)
{
    char dev[64];
    if (!path || strncmp(path, "/dev/", 5) != 0)
        return PATH_NONE;
    if (link_dir(path)) {
        for (int i = 0; i < n_cameras; i++)
            if (plugged(cameras[i])) {
                *out = cameras[i];
                return PATH_DIR;
            }
        return PATH_NONE;
    }
    for (int i = 0; i < n_cameras; i++) {
        struct camera *cam = cameras[i];
        if (!plugged(cam))
            continue;
        device_path(cam, dev, sizeof(dev));
        if (!strcmp(path, dev)) {
            *out = cam;
            return PATH_DEVICE;
        }
        if ((cam->by_id[0] && !strcmp(path, cam->by_id))
                || (cam->by_path[0] && !strcmp(path, cam->by_path))) {
            *out = cam;
            return PATH_LINK;
        }
    }
    return PATH_NONE;
}

static void link_target(struct camera *cam, char *buf, size_t size)
{
    snprintf(buf, size, "../../video%d", __atomic_load_n(&cam->state->node, __ATOMIC_ACQUIRE));
}

static void fill_stat(struct camera *cam, int kind, struct stat *st)
{
    memset(st, 0, sizeof(*st));
    int node = __atomic_load_n(&cam->state->node, __ATOMIC_ACQUIRE);
    st->st_dev = makedev(0, 5);
    st->st_nlink = 1;
    st->st_blksize = 4096;
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    st->st_atim = st->st_mtim = st->st_ctim = now;
    if (kind == PATH_DIR) {
        st->st_mode = S_IFDIR | 0755;
        st->st_nlink = 2;
        st->st_size = 4096;
        st->st_ino = 0x7d000;
    } else if (kind == PATH_DEVICE) {
        st->st_mode = S_IFCHR | 0660;
        st->st_rdev = makedev(81, (unsigned)node);
        st->st_gid = 44;  /* video */
        st->st_ino = 0x7e000 + (ino_t)node;
    } else {
        char target[64];
        link_target(cam, target, sizeof(target));
        st->st_mode = S_IFLNK | 0777;
        st->st_size = (off_t)strlen(target);
        st->st_ino = 0x7f000 + (ino_t)node * 2 + (ino_t)(cam - cameras[0] >= 0);
    }
}

static void fill_statx(struct camera *cam, int kind, struct statx *sx)
{
    struct stat st;
    fill_stat(cam, kind, &st);
    memset(sx, 0, sizeof(*sx));
    sx->stx_mask = STATX_BASIC_STATS;
    sx->stx_blksize = (uint32_t)st.st_blksize;
    sx->stx_nlink = (uint32_t)st.st_nlink;
    sx->stx_uid = st.st_uid;
    sx->stx_gid = st.st_gid;
    sx->stx_mode = (uint16_t)st.st_mode;
    sx->stx_ino = st.st_ino;
    sx->stx_size = (uint64_t)st.st_size;
    sx->stx_rdev_major = major(st.st_rdev);
    sx->stx_rdev_minor = minor(st.st_rdev);
    sx->stx_dev_major = major(st.st_dev);
    sx->stx_dev_minor = minor(st.st_dev);
    sx->stx_atime.tv_sec = st.st_atim.tv_sec;
    sx->stx_mtime.tv_sec = st.st_mtim.tv_sec;
    sx->stx_ctime.tv_sec = st.st_ctim.tv_sec;
}

/* ------------------------------------------------------------------ handles */

static int dead(struct handle *h)
{
    struct shared_state *s = h->cam->state;
    return !__atomic_load_n(&s->plugged, __ATOMIC_ACQUIRE)
        || __atomic_load_n(&s->generation, __ATOMIC_ACQUIRE) != h->generation;
}

static struct handle *lookup(int fd)
{
    if (fd < 0 || fd >= MAX_FDS || !n_cameras || !table_is_ours())
        return NULL;
    pthread_mutex_lock(&table_lock);
    struct handle *h = handles[fd];
    pthread_mutex_unlock(&table_lock);
    if (!h)
        return NULL;
    /* A descriptor closed behind our back (close_range, dup2) is not ours any more. */
    struct stat st;
    if (real_fstat(fd, &st) != 0 || st.st_ino != h->ino) {
        pthread_mutex_lock(&table_lock);
        if (handles[fd] == h)
            handles[fd] = NULL;
        pthread_mutex_unlock(&table_lock);
        return NULL;
    }
    return h;
}

/* Keep the eventfd readable exactly when poll on the device would report something. */
static void sync_event(struct handle *h)
{
    int ready = !h->streaming || h->dead || h->n_done > 0;
    uint64_t v = 1;
    if (ready && !h->event_set) {
        if (write(h->efd, &v, sizeof(v)) == sizeof(v))
            h->event_set = 1;
    } else if (!ready && h->event_set) {
        if (real_read(h->efd, &v, sizeof(v)) == sizeof(v) || errno == EAGAIN)
            h->event_set = 0;
    }
}

static int open_device(struct camera *cam, int flags)
{
    if (__atomic_load_n(&cam->state->denied, __ATOMIC_ACQUIRE)) {
        errno = EACCES;
        return -1;
    }
    if (flags & O_DIRECTORY) {
        errno = ENOTDIR;
        return -1;
    }
    struct handle *h = calloc(1, sizeof(*h));
    if (!h) {
        errno = ENOMEM;
        return -1;
    }
    int fd = eventfd(0, EFD_NONBLOCK | ((flags & O_CLOEXEC) ? EFD_CLOEXEC : 0));
    if (fd < 0) {
        free(h);
        return -1;
    }
    if (fd >= MAX_FDS) {
        real_close(fd);
        free(h);
        errno = EMFILE;
        return -1;
    }
    struct stat st;
    real_fstat(fd, &st);
    h->fd = fd;
    h->refs = 1;
    h->efd = real_fcntl(fd, F_DUPFD_CLOEXEC, 0);
    h->ino = st.st_ino;
    h->cam = cam;
    h->generation = __atomic_load_n(&cam->state->generation, __ATOMIC_ACQUIRE);
    h->memfd = -1;
    h->memory = V4L2_MEMORY_MMAP;
    h->nonblock = (flags & O_NONBLOCK) != 0;
    pthread_mutex_init(&h->lock, NULL);
    pthread_cond_init(&h->cond, NULL);
    pthread_mutex_lock(&table_lock);
    uint32_t token = ++next_token & 0xFFFF;
    h->owner_id = ((uint64_t)getpid() << 42) | (instance_id << 16) | token;
    handles[fd] = h;
    pthread_mutex_unlock(&table_lock);
    sync_event(h);
    return fd;
}

/* Any real open that returns a number we still hold means that entry is stale. */
static int forget_stale(int fd)
{
    if (fd >= 0 && fd < MAX_FDS && n_cameras && table_is_ours()) {
        pthread_mutex_lock(&table_lock);
        struct handle *h = handles[fd];
        handles[fd] = NULL;
        pthread_mutex_unlock(&table_lock);
        (void)h;  /* leaked on purpose: another thread may still hold it */
    }
    return fd;
}

static int emulated_open(const char *path, int flags, int *result)
{
    struct camera *cam;
    int kind = match_path(path, &cam);
    if (kind == PATH_NONE || kind == PATH_DIR)
        return 0;
    if (kind == PATH_LINK && (flags & O_NOFOLLOW)) {
        errno = ELOOP;
        *result = -1;
        return 1;
    }
    *result = open_device(cam, flags);
    return 1;
}

/* ------------------------------------------------------------------ ownership */

static int owner_alive(uint64_t owner)
{
    pid_t pid = (pid_t)(owner >> 42);
    if (pid == getpid())
        return ((owner >> 16) & 0x3FFFFFF) == instance_id;
    return kill(pid, 0) == 0 || errno == EPERM;
}

static int acquire(struct handle *h)
{
    uint64_t *slot = &h->cam->state->owner;
    for (;;) {
        uint64_t cur = __atomic_load_n(slot, __ATOMIC_ACQUIRE);
        if (cur == h->owner_id)
            return 0;
        if (cur && owner_alive(cur))
            return EBUSY;
        if (__atomic_compare_exchange_n(slot, &cur, h->owner_id, 0, __ATOMIC_ACQ_REL,
                                        __ATOMIC_ACQUIRE))
            return 0;
    }
}

static int owns(struct handle *h)
{
    return __atomic_load_n(&h->cam->state->owner, __ATOMIC_ACQUIRE) == h->owner_id;
}

static void release_owner(struct handle *h)
{
    uint64_t cur = h->owner_id;
    __atomic_compare_exchange_n(&h->cam->state->owner, &cur, 0, 0, __ATOMIC_ACQ_REL,
                                __ATOMIC_ACQUIRE);
}

/* ------------------------------------------------------------------ JPEG */

static uint8_t zigzag[64];     /* zigzag index -> natural index */
static float dct_cos[8][8];
static uint32_t crc_table[8][256];   /* [k][n]: the CRC of byte n followed by k zero bytes */
static pthread_once_t jpeg_once = PTHREAD_ONCE_INIT;

static void jpeg_init(void)
{
    for (uint32_t n = 0; n < 256; n++) {
        uint32_t c = n;
        for (int k = 0; k < 8; k++)
            c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        crc_table[0][n] = c;
    }
    for (int k = 1; k < 8; k++)
        for (int n = 0; n < 256; n++)
            crc_table[k][n] = (crc_table[k - 1][n] >> 8) ^ crc_table[0][crc_table[k - 1][n] & 0xFF];
    int k = 0;
    for (int s = 0; s < 15; s++) {
        if (s % 2 == 0) {
            for (int r = s < 8 ? s : 7; r >= 0 && s - r < 8; r--)
                zigzag[k++] = (uint8_t)(r * 8 + (s - r));
        } else {
            for (int c = s < 8 ? s : 7; c >= 0 && s - c < 8; c--)
                zigzag[k++] = (uint8_t)((s - c) * 8 + c);
        }
    }
    for (int u = 0; u < 8; u++)
        for (int x = 0; x < 8; x++)
            dct_cos[u][x] = (float)(cos((2 * x + 1) * u * M_PI / 16.0)
                                    * (u == 0 ? sqrt(0.125) : 0.5));
}

/* Read the quantisation and Huffman tables a reference JPEG (the harness's) carries. */
static int parse_tables(struct camera *cam, const char *path)
{
    uint8_t buf[2048];
    size_t len = 0;
    pthread_once(&jpeg_once, jpeg_init);
    if (read_file(path, buf, sizeof(buf), &len) != 0 || len < 4 || len > sizeof(cam->tables))
        return -1;
    memcpy(cam->tables, buf, len);
    cam->tables_len = (uint32_t)len;
    int found = 0;
    size_t p = 0;
    while (p + 4 <= len && buf[p] == 0xFF) {
        uint8_t marker = buf[p + 1];
        size_t seg = ((size_t)buf[p + 2] << 8) | buf[p + 3];
        size_t end = p + 2 + seg, q = p + 4;
        if (end > len)
            return -1;
        if (marker == 0xDB) {
            while (q + 65 <= end) {
                int id = buf[q] & 15;
                if ((buf[q] >> 4) != 0 || id > 1)
                    return -1;
                for (int i = 0; i < 64; i++)
                    cam->quant[id][zigzag[i]] = buf[q + 1 + i];
                q += 65;
                found |= 1 << id;
            }
        } else if (marker == 0xC4) {
            while (q + 17 <= end) {
                int cls = buf[q] >> 4, id = buf[q] & 15;
                if (id > 1 || cls > 1)
                    return -1;
                int t = id * 2 + cls;
                const uint8_t *bits = buf + q + 1, *vals = buf + q + 17;
                uint32_t code = 0, n = 0;
                for (int l = 1; l <= 16; l++) {
                    for (int i = 0; i < bits[l - 1]; i++, n++) {
                        if (q + 17 + n >= end)
                            return -1;
                        cam->huff_code[t][vals[n]] = (uint16_t)code++;
                        cam->huff_size[t][vals[n]] = (uint8_t)l;
                    }
                    code <<= 1;
                }
                q += 17 + n;
                found |= 4 << t;
            }
        }
        p = end;
    }
    return found == 0x3F ? 0 : -1;
}

struct bitwriter {
    uint8_t *out;
    size_t len, cap;
    uint32_t acc;
    int nbits;
};

static void put_bits(struct bitwriter *w, uint32_t code, int size)
{
    w->acc = (w->acc << size) | (code & ((1u << size) - 1));
    w->nbits += size;
    while (w->nbits >= 8) {
        uint8_t byte = (uint8_t)(w->acc >> (w->nbits - 8));
        w->nbits -= 8;
        if (w->len + 2 <= w->cap) {
            w->out[w->len++] = byte;
            if (byte == 0xFF)
                w->out[w->len++] = 0;
        } else {
            w->len = w->cap + 1;  /* overflow, noticed by the caller */
        }
    }
}

static void flush_bits(struct bitwriter *w)
{
    if (w->nbits > 0)
        put_bits(w, 0x7F, 8 - w->nbits);
    w->acc = 0;
}

static int magnitude_bits(int v)
{
    int a = v < 0 ? -v : v, n = 0;
    while (a) {
        n++;
        a >>= 1;
    }
    return n;
}

static void encode_block(struct camera *cam, struct bitwriter *w, const float *in, int table,
                         int *pred)
{
    float tmp[64];
    int coef[64];
    for (int y = 0; y < 8; y++)
        for (int u = 0; u < 8; u++) {
            float s = 0;
            for (int x = 0; x < 8; x++)
                s += in[y * 8 + x] * dct_cos[u][x];
            tmp[y * 8 + u] = s;
        }
    for (int v = 0; v < 8; v++)
        for (int u = 0; u < 8; u++) {
            float s = 0;
            for (int y = 0; y < 8; y++)
                s += tmp[y * 8 + u] * dct_cos[v][y];
            float q = s / cam->quant[table][v * 8 + u];
            coef[v * 8 + u] = (int)lrintf(q);
        }
    int dc_t = table * 2, ac_t = table * 2 + 1;
    int diff = coef[0] - *pred;
    *pred = coef[0];
    int n = magnitude_bits(diff);
    put_bits(w, cam->huff_code[dc_t][n], cam->huff_size[dc_t][n]);
    if (n)
        put_bits(w, (uint32_t)(diff < 0 ? diff - 1 : diff), n);
    int run = 0;
    for (int k = 1; k < 64; k++) {
        int c = coef[zigzag[k]];
        if (!c) {
            run++;
            continue;
        }
        while (run > 15) {
            put_bits(w, cam->huff_code[ac_t][0xF0], cam->huff_size[ac_t][0xF0]);
            run -= 16;
        }
        n = magnitude_bits(c);
        int sym = (run << 4) | n;
        put_bits(w, cam->huff_code[ac_t][sym], cam->huff_size[ac_t][sym]);
        put_bits(w, (uint32_t)(c < 0 ? c - 1 : c), n);
        run = 0;
    }
    if (run)
        put_bits(w, cam->huff_code[ac_t][0], cam->huff_size[ac_t][0]);
}

/* One 16x8 MCU of a YUYV image (Y Y Cb Cr, 4:2:2), as its own restart interval. */
static void encode_mcu(struct camera *cam, struct bitwriter *w, const uint8_t *yuyv,
                       uint32_t width, uint32_t height, uint32_t mx, uint32_t my)
{
    float y0[64], y1[64], cb[64], cr[64];
    for (int r = 0; r < 8; r++) {
        uint32_t y = my * 8 + (uint32_t)r;
        if (y >= height)
            y = height - 1;
        const uint8_t *row = yuyv + (size_t)y * width * 2;
        for (int c = 0; c < 16; c++) {
            uint32_t x = mx * 16 + (uint32_t)c;
            if (x >= width)
                x = width - 1;
            /* V4L2's YUYV is video range, JFIF full range (as a camera's encoder makes it) */
            float luma = ((float)row[x * 2] - 16.0f) * (255.0f / 219.0f) - 128.0f;
            if (c < 8)
                y0[r * 8 + c] = luma;
            else
                y1[r * 8 + c - 8] = luma;
            if (c % 2 == 0) {
                uint32_t pair = (x & ~1u) * 2;
                cb[r * 8 + c / 2] = ((float)row[pair + 1] - 128.0f) * (255.0f / 224.0f);
                cr[r * 8 + c / 2] = ((float)row[pair + 3] - 128.0f) * (255.0f / 224.0f);
            }
        }
    }
    int pred[3] = {0, 0, 0};
    encode_block(cam, w, y0, 0, &pred[0]);
    encode_block(cam, w, y1, 0, &pred[0]);
    encode_block(cam, w, cb, 1, &pred[1]);
    encode_block(cam, w, cr, 1, &pred[2]);
    flush_bits(w);
}

struct jpeg_cache {
    uint64_t look;
    uint32_t width, height, mcus_x, mcus_y;
    uint8_t header[4096];
    uint32_t header_len;
    uint8_t *data;            /* every MCU of the background, each byte-aligned */
    uint32_t *offset, *length;
};

static void put16(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 8);
    p[1] = (uint8_t)v;
}

static struct jpeg_cache *jpeg_cache_for(struct camera *cam, uint32_t fmt, uint32_t frame,
                                         const uint8_t *background, uint64_t look)
{
    pthread_mutex_lock(&cam->lock);
    struct jpeg_cache *jc = cam->jcache[fmt][frame];
    if (jc && jc->look == look) {
        pthread_mutex_unlock(&cam->lock);
        return jc;
    }
    if (jc) {                 /* the controls changed the picture: encode it again */
        free(jc->data);
        free(jc->offset);
        free(jc->length);
        free(jc);
        cam->jcache[fmt][frame] = NULL;
    }
    const struct frame_desc *fd = &cam->formats[fmt].frames[frame];
    jc = calloc(1, sizeof(*jc));
    jc->look = look;
    jc->width = fd->width;
    jc->height = fd->height;
    jc->mcus_x = (fd->width + 15) / 16;
    jc->mcus_y = (fd->height + 7) / 8;
    uint32_t n = jc->mcus_x * jc->mcus_y;
    jc->offset = calloc(n, sizeof(uint32_t));
    jc->length = calloc(n, sizeof(uint32_t));
    size_t cap = (size_t)fd->width * fd->height * 2 + 4096;
    jc->data = malloc(cap);
    struct bitwriter w = {jc->data, 0, cap, 0, 0};
    for (uint32_t i = 0; i < n; i++) {
        size_t start = w.len;
        encode_mcu(cam, &w, background, fd->width, fd->height, i % jc->mcus_x, i / jc->mcus_x);
        jc->offset[i] = (uint32_t)start;
        jc->length[i] = (uint32_t)(w.len - start);
    }
    /* SOI, JFIF APP0, the tables, SOF0 (4:2:2), DRI 1, SOS */
    uint8_t *h = jc->header;
    size_t p = 0;
    static const uint8_t soi_app0[] = {0xFF, 0xD8, 0xFF, 0xE0, 0, 16, 'J', 'F', 'I', 'F', 0,
                                       1, 1, 0, 0, 1, 0, 1, 0, 0};
    memcpy(h, soi_app0, sizeof(soi_app0));
    p = sizeof(soi_app0);
    memcpy(h + p, cam->tables, cam->tables_len);
    p += cam->tables_len;
    uint8_t sof[] = {0xFF, 0xC0, 0, 17, 8, 0, 0, 0, 0, 3, 1, 0x21, 0, 2, 0x11, 1, 3, 0x11, 1};
    put16(sof + 5, fd->height);
    put16(sof + 7, fd->width);
    memcpy(h + p, sof, sizeof(sof));
    p += sizeof(sof);
    static const uint8_t dri[] = {0xFF, 0xDD, 0, 4, 0, 1};
    memcpy(h + p, dri, sizeof(dri));
    p += sizeof(dri);
    static const uint8_t sos[] = {0xFF, 0xDA, 0, 12, 3, 1, 0x00, 2, 0x11, 3, 0x11, 0, 63, 0};
    memcpy(h + p, sos, sizeof(sos));
    p += sizeof(sos);
    jc->header_len = (uint32_t)p;
    cam->jcache[fmt][frame] = jc;
    pthread_mutex_unlock(&cam->lock);
    return jc;
}

/* ------------------------------------------------------------------ frames */

static uint8_t crc8(const uint8_t *data, int n)
{
    uint8_t crc = 0;
    for (int i = 0; i < n; i++) {
        crc ^= data[i];
        for (int b = 0; b < 8; b++)
            crc = (crc & 0x80) ? (uint8_t)((crc << 1) ^ 0x07) : (uint8_t)(crc << 1);
    }
    return crc;
}

#define CODE_ROWS 4
#define CODE_COLS 11
#define LUMA_BLACK 16
#define LUMA_WHITE 235

/* The 4 x 11 blocks of the synthetic camera's frame code: corners fixed, 40 data bits. */
/* Whether each cell of frame `index`'s code is white: the corners fixed, then the 32 bits of
 * the index and its CRC-8, most significant first (py_vision's synthetic_picture). */
static void code_cells(uint64_t index, int on[CODE_ROWS][CODE_COLS])
{
    uint32_t value = (uint32_t)index;
    uint8_t payload[4] = {(uint8_t)(value >> 24), (uint8_t)(value >> 16), (uint8_t)(value >> 8),
                          (uint8_t)value};
    uint64_t word = ((uint64_t)value << 8) | crc8(payload, 4);
    int bit = 0;
    for (int r = 0; r < CODE_ROWS; r++) {
        for (int c = 0; c < CODE_COLS; c++) {
            int top = r == 0, bottom = r == CODE_ROWS - 1, left = c == 0,
                right = c == CODE_COLS - 1;
            if ((top || bottom) && (left || right))
                on[r][c] = (top && left) || (bottom && right);
            else
                on[r][c] = (int)((word >> (39 - bit++)) & 1);
        }
    }
}

static void draw_code(const struct frame_desc *fd, uint8_t *yuyv, uint64_t index)
{
    if (!fd->cell)
        return;
    int on[CODE_ROWS][CODE_COLS];
    code_cells(index, on);
    for (int r = 0; r < CODE_ROWS; r++) {
        for (int c = 0; c < CODE_COLS; c++) {
            uint8_t luma = on[r][c] ? LUMA_WHITE : LUMA_BLACK;
            for (uint32_t y = 0; y < fd->cell; y++) {
                uint8_t *row = yuyv + ((size_t)(fd->code_y + r * fd->cell + y) * fd->width
                                       + fd->code_x + c * fd->cell) * 2;
                for (uint32_t x = 0; x < fd->cell; x++)
                    row[x * 2] = luma;
            }
        }
    }
}

/* A raw format's code: each cell's bytes, plane by plane, from the picture with that cell
 * white or black (the harness made both with the format's own layout). */
static void draw_raw_code(const struct format_desc *fmt, const struct frame_desc *fd,
                          uint8_t *out, const uint8_t *black, const uint8_t *white,
                          uint64_t index)
{
    if (!fd->cell)
        return;
    int on[CODE_ROWS][CODE_COLS];
    code_cells(index, on);
    const struct plane_desc *first = &fmt->planes[0];
    for (int r = 0; r < CODE_ROWS; r++) {
        for (int c = 0; c < CODE_COLS; c++) {
            const uint8_t *src = on[r][c] ? white : black;
            uint32_t x0 = fd->code_x + c * fd->cell, y0 = fd->code_y + r * fd->cell;
            size_t offset = 0;
            for (uint32_t p = 0; p < fmt->n_planes; p++) {
                const struct plane_desc *pl = &fmt->planes[p];
                size_t stride = (size_t)fd->bytesperline * pl->across * first->per
                    / (pl->per * first->across);
                uint32_t rows = (fd->height + pl->down - 1) / pl->down;
                size_t from = (size_t)x0 * pl->across / pl->per;
                size_t to = ((size_t)(x0 + fd->cell) * pl->across + pl->per - 1) / pl->per;
                for (uint32_t y = y0 / pl->down; y <= (y0 + fd->cell - 1) / pl->down; y++) {
                    size_t at = offset + y * stride + from;
                    memcpy(out + at, src + at, to - from);
                }
                offset += rows * stride;
            }
        }
    }
}

static int inactive(struct camera *cam, const struct control_desc *c);

/* A key for the control values that change the picture: 0 when none does. */
static uint64_t look_key(struct camera *cam)
{
    uint64_t key = 0;
    for (uint32_t i = 0; i < cam->n_controls; i++) {
        const struct control_desc *c = &cam->controls[i];
        if (!c->effect || inactive(cam, c))
            continue;
        int32_t v = __atomic_load_n(&cam->state->values[i], __ATOMIC_ACQUIRE);
        if (v == c->def)
            continue;
        key = (key ^ ((uint64_t)i << 32 | (uint32_t)v)) * 1099511628211ull + 1;
    }
    return key;
}

static uint8_t clamp8(float v)
{
    return v < 0 ? 0 : v > 255 ? 255 : (uint8_t)lrintf(v);
}

/* The picture as the controls make it: brightness, contrast, gain and exposure on luma,
 * saturation and a manual white balance on chroma. */
static void apply_look(struct camera *cam, const uint8_t *src, uint8_t *dst, size_t size)
{
    float bright = 0, contrast = 1, gain = 1, sat = 1, wb = 0;
    for (uint32_t i = 0; i < cam->n_controls; i++) {
        const struct control_desc *c = &cam->controls[i];
        if (!c->effect || inactive(cam, c))
            continue;
        float v = (float)__atomic_load_n(&cam->state->values[i], __ATOMIC_ACQUIRE);
        float d = (float)c->def, range = (float)(c->maximum - c->minimum);
        float ratio = d > 0 ? v / d : 1 + (v - d) / (range > 0 ? range : 1);
        switch (c->effect) {
        case FX_BRIGHTNESS:
            bright += (v - d) * 127.0f / (range > 0 ? range : 1);
            break;
        case FX_CONTRAST:
            contrast *= ratio;
            break;
        case FX_SATURATION:
            sat *= ratio;
            break;
        case FX_GAIN:
            gain *= 1 + (v - d) / (range > 0 ? range : 1);
            break;
        case FX_EXPOSURE:
            gain *= ratio;
            break;
        case FX_WHITE_BALANCE:
            wb += (d - v) / 50.0f;     /* lower temperatures bluer */
            break;
        default:
            break;
        }
    }
    uint8_t ly[256], lu[256], lv[256];
    for (int i = 0; i < 256; i++) {
        ly[i] = clamp8((((float)i - 128) * contrast + 128 + bright - 16) * gain + 16);
        lu[i] = clamp8(((float)i - 128) * sat + 128 + wb);
        lv[i] = clamp8(((float)i - 128) * sat + 128 - wb);
    }
    for (size_t p = 0; p + 3 < size; p += 4) {
        dst[p] = ly[src[p]];
        dst[p + 1] = lu[src[p + 1]];
        dst[p + 2] = ly[src[p + 2]];
        dst[p + 3] = lv[src[p + 3]];
    }
}

/* The background of a size as the controls make it now, and the key of that look. */
static const uint8_t *background_for(struct camera *cam, uint32_t fmt, uint32_t frame,
                                     uint64_t *look)
{
    const struct frame_desc *fd = &cam->formats[fmt].frames[frame];
    size_t size = (size_t)fd->width * fd->height * 2;
    uint32_t slot = fmt * MAX_FRAMES + frame;
    uint64_t key = look_key(cam);
    pthread_mutex_lock(&cam->lock);
    if (!cam->backgrounds[slot]) {
        uint8_t *bg = malloc(size);
        size_t got = 0;
        if (bg && (read_file(fd->background, bg, size, &got) != 0 || got != size)) {
            /* no picture: mid grey with neutral chroma */
            for (size_t i = 0; i < size; i += 2) {
                bg[i] = 128;
                bg[i + 1] = 128;
            }
        }
        cam->backgrounds[slot] = bg;
    }
    const uint8_t *result = cam->backgrounds[slot];
    if (key) {
        if (!cam->looks[slot])
            cam->looks[slot] = malloc(size);
        if (cam->look_keys[slot] != key) {
            apply_look(cam, cam->backgrounds[slot], cam->looks[slot], size);
            cam->look_keys[slot] = key;
        }
        result = cam->looks[slot];
    }
    pthread_mutex_unlock(&cam->lock);
    *look = key;
    return result;
}

/* A raw format's two pictures of a size (every code cell black, every cell white). */
static void raw_pictures(struct camera *cam, uint32_t fmt, uint32_t frame,
                         const uint8_t **black, const uint8_t **white)
{
    const struct frame_desc *fd = &cam->formats[fmt].frames[frame];
    uint32_t slot = fmt * MAX_FRAMES + frame;
    pthread_mutex_lock(&cam->lock);
    if (!cam->backgrounds[slot]) {
        uint8_t *b = calloc(1, fd->sizeimage), *w = calloc(1, fd->sizeimage);
        size_t got = 0;
        if (b)
            read_file(fd->background, b, fd->sizeimage, &got);
        if (w)
            read_file(fd->white, w, fd->sizeimage, &got);
        cam->backgrounds[slot] = b;
        cam->whites[slot] = w;
    }
    *black = cam->backgrounds[slot];
    *white = cam->whites[slot];
    pthread_mutex_unlock(&cam->lock);
}

/* How frame `index` is broken (0 truncate, 1 garbage, 2 no EOI), or -1: it is whole. */
static int corrupt_mode_of(const struct camera *cam, uint64_t index)
{
    uint32_t every = cam->corrupt_every;
    if (!every || index % every != every - 1)
        return -1;
    return cam->corrupt_mode == 3 ? (int)((index / every) % 3) : cam->corrupt_mode;
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* The CRC-32 zlib computes (reflected, polynomial 0xEDB88320), so Python's zlib.crc32 agrees;
 * eight bytes per step through the tables (about 1 GB/s), the tail a byte at a time. */
static uint32_t crc32_of(const uint8_t *data, size_t len)
{
    const uint32_t (*t)[256] = crc_table;
    uint32_t c = 0xFFFFFFFFu;
    size_t i = 0;
    for (; i + 8 <= len; i += 8) {
        uint32_t a = c ^ le32(data + i), b = le32(data + i + 4);
        c = t[7][a & 0xFF] ^ t[6][(a >> 8) & 0xFF] ^ t[5][(a >> 16) & 0xFF] ^ t[4][a >> 24]
            ^ t[3][b & 0xFF] ^ t[2][(b >> 8) & 0xFF] ^ t[1][(b >> 16) & 0xFF] ^ t[0][b >> 24];
    }
    for (; i < len; i++)
        c = t[0][(c ^ data[i]) & 0xFF] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

/* Write a dequeued JPEG's record into the served ring (called with h->lock held). */
static void record_served(struct handle *h, const struct buffer *buf)
{
    struct served_record *r = &h->cam->served[buf->index % SERVED_SLOTS];
    __atomic_store_n(&r->tag, 0, __ATOMIC_RELEASE);
    __atomic_thread_fence(__ATOMIC_SEQ_CST);
    r->length = buf->bytesused;
    r->flags = buf->flags;
    r->crc = buf->crc;
    __atomic_store_n(&r->tag, buf->index + 1, __ATOMIC_RELEASE);
}

static uint32_t render_jpeg(struct handle *h, uint8_t *out, size_t cap, uint64_t index)
{
    struct camera *cam = h->cam;
    const struct frame_desc *fd = &cam->formats[h->fmt].frames[h->frame];
    uint64_t look;
    const uint8_t *bg = background_for(cam, h->fmt, h->frame, &look);
    struct jpeg_cache *jc = jpeg_cache_for(cam, h->fmt, h->frame, bg, look);
    size_t frame_size = (size_t)fd->width * fd->height * 2;
    if (!h->scratch || h->scratch_look != look) {
        if (!h->scratch)
            h->scratch = malloc(frame_size);
        memcpy(h->scratch, bg, frame_size);
        h->scratch_look = look;
    }
    draw_code(fd, h->scratch, index);
    uint32_t mx0 = 1, mx1 = 0, my0 = 1, my1 = 0;
    if (fd->cell) {
        mx0 = fd->code_x / 16;
        mx1 = (fd->code_x + CODE_COLS * fd->cell - 1) / 16;
        my0 = fd->code_y / 8;
        my1 = (fd->code_y + CODE_ROWS * fd->cell - 1) / 8;
    }
    size_t p = jc->header_len;
    if (p > cap)
        return 0;
    memcpy(out, jc->header, p);
    uint32_t n = jc->mcus_x * jc->mcus_y;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t mx = i % jc->mcus_x, my = i / jc->mcus_x;
        if (mx >= mx0 && mx <= mx1 && my >= my0 && my <= my1) {
            struct bitwriter w = {out + p, 0, cap - p - 4, 0, 0};
            encode_mcu(cam, &w, h->scratch, fd->width, fd->height, mx, my);
            if (w.len > w.cap)
                return 0;
            p += w.len;
        } else {
            if (p + jc->length[i] + 4 > cap)
                return 0;
            memcpy(out + p, jc->data + jc->offset[i], jc->length[i]);
            p += jc->length[i];
        }
        out[p++] = 0xFF;
        out[p++] = i + 1 < n ? (uint8_t)(0xD0 + i % 8) : 0xD9;
    }
    int mode = corrupt_mode_of(cam, index);
    if (mode >= 0) {
        if (mode == 0) {
            p = jc->header_len + (p - jc->header_len) / 3;   /* cut inside the scan */
        } else if (mode == 1) {
            uint32_t x = (uint32_t)index * 2654435761u;
            for (size_t i = 2; i < p; i++) {               /* garbage after SOI */
                x = x * 1103515245u + 12345u;
                out[i] = (uint8_t)(x >> 16);
                if (out[i] == 0xFF)
                    out[i] = 0xFE;
            }
        } else {
            p -= 2;                                         /* no EOI */
        }
    }
    return (uint32_t)p;
}

/* Read a clip and find its access units (called with cam->lock held); 0 or -1. */
static int load_clip(struct format_desc *fmt)
{
    struct clip *c = &fmt->clip;
    uint8_t *data = fmt->clip_size >= 5 ? malloc(fmt->clip_size) : NULL;
    size_t got = 0;
    if (!data || read_file(fmt->clip_path, data, fmt->clip_size, &got) != 0
            || got != fmt->clip_size) {
        free(data);
        return -1;
    }
    uint32_t n_units = 0;
    for (size_t i = 0; i + 5 <= got; i++)
        if (!memcmp(data + i, "\0\0\0\1\x09", 5))
            n_units++;
    if (!n_units) {
        free(data);
        return -1;
    }
    c->offset = calloc(n_units, sizeof(uint32_t));
    c->length = calloc(n_units, sizeof(uint32_t));
    if (!c->offset || !c->length) {
        free(c->offset);
        free(c->length);
        free(data);
        return -1;
    }
    uint32_t k = 0;
    for (size_t i = 0; i + 5 <= got; i++)
        if (!memcmp(data + i, "\0\0\0\1\x09", 5))
            c->offset[k++] = (uint32_t)i;
    for (k = 0; k < n_units; k++)
        c->length[k] = (k + 1 < n_units ? c->offset[k + 1] : (uint32_t)got) - c->offset[k];
    c->data = data;
    c->len = got;
    c->n_units = n_units;
    return 0;
}

/* A video format's frame: the clip's access unit for the sensor's frame, as it is. */
static uint32_t render_clip(struct handle *h, uint8_t *out, size_t cap, uint64_t index)
{
    struct camera *cam = h->cam;
    struct format_desc *fmt = &cam->formats[h->fmt];
    pthread_mutex_lock(&cam->lock);
    int ok = fmt->clip.n_units || load_clip(fmt) == 0;
    pthread_mutex_unlock(&cam->lock);
    if (!ok)
        return 0;
    uint32_t unit = (uint32_t)(index % fmt->clip.n_units);
    uint32_t length = fmt->clip.length[unit];
    if (length > cap)
        return 0;
    memcpy(out, fmt->clip.data + fmt->clip.offset[unit], length);
    return length;
}

/* Where buffer b's bytes are: our mapping (MMAP) or the program's memory (USERPTR). */
static uint8_t *buffer_memory(struct handle *h, uint32_t b)
{
    return h->memory == V4L2_MEMORY_USERPTR ? h->buffers[b].user
                                            : h->mem + (size_t)b * h->stride;
}

static uint32_t render_frame(struct handle *h, uint32_t b, uint64_t index)
{
    struct camera *cam = h->cam;
    const struct format_desc *fmt = &cam->formats[h->fmt];
    const struct frame_desc *fd = &fmt->frames[h->frame];
    uint8_t *out = buffer_memory(h, b);
    if (fmt->clip_path[0])
        return render_clip(h, out, fd->sizeimage, index);
    if (fmt->fourcc == V4L2_PIX_FMT_MJPEG && cam->have_tables)
        return render_jpeg(h, out, fd->sizeimage, index);
    if (fmt->n_planes) {
        const uint8_t *black, *white;
        raw_pictures(cam, h->fmt, h->frame, &black, &white);
        if (!black || !white)
            return 0;
        if (h->buffers[b].bg_frame != (int)(h->fmt * MAX_FRAMES + h->frame)) {
            memcpy(out, black, fd->sizeimage);
            h->buffers[b].bg_frame = (int)(h->fmt * MAX_FRAMES + h->frame);
        }
        draw_raw_code(fmt, fd, out, black, white, index);
        return fd->sizeimage;
    }
    size_t size = (size_t)fd->width * fd->height * 2;
    uint64_t look;
    const uint8_t *bg = background_for(cam, h->fmt, h->frame, &look);
    if (h->buffers[b].bg_frame != (int)(h->fmt * MAX_FRAMES + h->frame)
            || h->buffers[b].bg_look != look) {
        memcpy(out, bg, size);
        h->buffers[b].bg_frame = (int)(h->fmt * MAX_FRAMES + h->frame);
        h->buffers[b].bg_look = look;
    }
    draw_code(fd, out, index);
    return (uint32_t)size;
}

static double now_mono(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void sleep_for(double seconds)
{
    if (seconds <= 0)
        return;
    struct timespec ts = {(time_t)seconds, (long)((seconds - (time_t)seconds) * 1e9)};
    while (nanosleep(&ts, &ts) == -1 && errno == EINTR) {
    }
}

static void *producer(void *arg)
{
    struct handle *h = arg;
    struct shared_state *s = h->cam->state;
    sigset_t all;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, NULL);
    double period = (double)h->interval.numerator / h->interval.denominator;
    double start = now_mono();
    uint64_t slot = 1;
    for (;;) {
        double due = start + slot * period;
        /* wait for the frame's time in short steps, watching for an unplug */
        for (;;) {
            pthread_mutex_lock(&h->lock);
            int stop = h->stop;
            if (!h->dead && dead(h)) {
                h->dead = 1;
                sync_event(h);
                pthread_cond_broadcast(&h->cond);
            }
            int gone = h->dead;
            pthread_mutex_unlock(&h->lock);
            if (stop || gone)
                return NULL;
            double left = due - now_mono();
            if (left <= 0)
                break;
            sleep_for(left < 0.02 ? left : 0.02);
        }
        double late = now_mono() - due;
        if (late > period)   /* fell behind (a loaded machine): skip the missed slots */
            slot += (uint64_t)(late / period);
        slot++;
        if (__atomic_load_n(&s->stalled, __ATOMIC_ACQUIRE))
            continue;
        uint64_t index = __atomic_fetch_add(&s->sensor_frames, 1, __ATOMIC_ACQ_REL);
        pthread_mutex_lock(&h->lock);
        uint32_t sequence = h->sequence++;
        struct camera *cam = h->cam;
        int lost = cam->drop_every && index % cam->drop_every == cam->drop_every - 1;
        if (!h->n_queued || lost) {   /* no buffer, or lost on the way: as in uvcvideo */
            pthread_mutex_unlock(&h->lock);
            continue;
        }
        uint32_t b = h->queued[0];
        memmove(h->queued, h->queued + 1, --h->n_queued * sizeof(uint32_t));
        h->in_flight++;
        pthread_mutex_unlock(&h->lock);
        int error = cam->error_every && index % cam->error_every == cam->error_every - 1;
        struct timespec c0, c1;
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
        uint32_t used = error ? 0 : render_frame(h, b, index);
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
        __atomic_fetch_add(&s->render_ns, (uint64_t)((c1.tv_sec - c0.tv_sec) * 1000000000LL
                                                     + (c1.tv_nsec - c0.tv_nsec)),
                           __ATOMIC_ACQ_REL);
        /* A JPEG's or a clip's bytes vary frame to frame: the served ring records them. */
        const struct format_desc *made = &h->cam->formats[h->fmt];
        int jpeg = !error && h->cam->served && (made->clip_path[0] || (h->cam->have_tables
            && made->fourcc == V4L2_PIX_FMT_MJPEG));
        uint32_t crc = jpeg ? crc32_of(buffer_memory(h, b), used) : 0;
        struct timeval tv = {(time_t)due, (suseconds_t)((due - (time_t)due) * 1e6)};
        pthread_mutex_lock(&h->lock);
        struct buffer *buf = &h->buffers[b];
        buf->bytesused = used;
        buf->sequence = sequence;
        buf->timestamp = tv;
        buf->jpeg = jpeg;
        buf->error = error;
        buf->crc = crc;
        buf->flags = corrupt_mode_of(h->cam, index) >= 0 ? SERVED_CORRUPT : 0;
        buf->index = index;
        buf->state = BUF_DONE;
        h->in_flight--;
        h->done[h->n_done++] = b;
        __atomic_fetch_add(&s->frames_served, 1, __ATOMIC_ACQ_REL);
        sync_event(h);
        pthread_cond_broadcast(&h->cond);
        pthread_mutex_unlock(&h->lock);
    }
}

static void bus_lock(struct bus_state *bus)
{
    while (__atomic_exchange_n(&bus->lock, 1, __ATOMIC_ACQUIRE))
        sched_yield();
}

static void bus_unlock(struct bus_state *bus)
{
    __atomic_store_n(&bus->lock, 0, __ATOMIC_RELEASE);
}

/* The bytes per microframe uvcvideo reserves for the current format: a compressed one what
 * the camera asks (dwMaxPayloadTransferSize), a raw one its frames' bytes at its rate, each
 * rounded up to an alternate setting of the endpoint. */
static uint32_t bus_need(struct handle *h)
{
    struct camera *cam = h->cam;
    const struct format_desc *fmt = &cam->formats[h->fmt];
    double need = cam->compressed_payload;
    if (!(fmt->flags & V4L2_FMT_FLAG_COMPRESSED))
        need = (double)fmt->frames[h->frame].sizeimage * h->interval.denominator
               / h->interval.numerator / 8000.0;
    for (uint32_t i = 0; i < cam->n_alts; i++)
        if (cam->alts[i] >= need)
            return cam->alts[i];
    return cam->n_alts ? cam->alts[cam->n_alts - 1] : (uint32_t)need;
}

/* Reserve the stream's bandwidth on the camera's bus: 0, or ENOSPC when others hold it. */
static int bus_reserve(struct handle *h)
{
    struct camera *cam = h->cam;
    struct bus_state *bus = cam->bus;
    if (!bus || !cam->bus_key)
        return 0;
    uint32_t need = bus_need(h), taken = 0;
    bus_lock(bus);
    struct bus_slot *own = NULL, *free_slot = NULL;
    for (int i = 0; i < BUS_SLOTS; i++) {
        struct bus_slot *s = &bus->slots[i];
        if (s->key == cam->bus_key)
            own = s;
        else if (s->key && owner_alive(s->owner))
            taken += s->bytes;
        else if (!free_slot)
            free_slot = s;
    }
    struct bus_slot *slot = own ? own : free_slot;
    if (!slot || taken + need > BUS_CAPACITY) {
        bus_unlock(bus);
        return ENOSPC;
    }
    slot->key = cam->bus_key;
    slot->owner = h->owner_id;
    slot->bytes = need;
    bus_unlock(bus);
    return 0;
}

static void bus_release(struct handle *h)
{
    struct bus_state *bus = h->cam->bus;
    if (!bus || !h->cam->bus_key)
        return;
    bus_lock(bus);
    for (int i = 0; i < BUS_SLOTS; i++)
        if (bus->slots[i].key == h->cam->bus_key && bus->slots[i].owner == h->owner_id)
            memset(&bus->slots[i], 0, sizeof(bus->slots[i]));
    bus_unlock(bus);
}

/* Called with h->lock held; returns with it held. */
static void stop_streaming(struct handle *h)
{
    if (!h->streaming)
        return;
    h->stop = 1;
    pthread_cond_broadcast(&h->cond);
    if (!h->forked) {
        pthread_mutex_unlock(&h->lock);
        pthread_join(h->thread, NULL);
        pthread_mutex_lock(&h->lock);
    }
    h->streaming = 0;
    h->stop = 0;
    bus_release(h);
    h->n_queued = h->n_done = 0;
    for (uint32_t i = 0; i < h->n_buffers; i++)
        h->buffers[i].state = BUF_IDLE;
    sync_event(h);
}

static void free_buffers(struct handle *h)
{
    if (h->mem)
        munmap(h->mem, h->stride * h->n_buffers);
    if (h->memfd >= 0)
        real_close(h->memfd);
    h->mem = NULL;
    h->memfd = -1;
    h->n_buffers = 0;
    free(h->scratch);
    h->scratch = NULL;
}

/* ------------------------------------------------------------------ ioctls */

static struct control_desc *find_control(struct camera *cam, uint32_t id, int *index)
{
    for (uint32_t i = 0; i < cam->n_controls; i++)
        if (cam->controls[i].id == id) {
            if (index)
                *index = (int)i;
            return &cam->controls[i];
        }
    return NULL;
}

/* The kernel's classes of control: a value behind a pointer (a string, an array, a compound
 * type) is read and written only through the EXT_CTRLS payload; INTEGER64 only as value64;
 * the rest also with G/S_CTRL. */
static int is_compound(const struct control_desc *c)
{
    return c->n_dims > 0 || c->type >= V4L2_CTRL_COMPOUND_TYPES;
}

static int is_pointer(const struct control_desc *c)
{
    return is_compound(c) || c->type == V4L2_CTRL_TYPE_STRING;
}

static int is_int(const struct control_desc *c)
{
    return !is_pointer(c) && c->type != V4L2_CTRL_TYPE_INTEGER64;
}

static int64_t control_value(struct camera *cam, int index)
{
    if (cam->controls[index].type == V4L2_CTRL_TYPE_INTEGER64)
        return __atomic_load_n(&cam->state->wide[index], __ATOMIC_ACQUIRE);
    return __atomic_load_n(&cam->state->values[index], __ATOMIC_ACQUIRE);
}

static int inactive(struct camera *cam, const struct control_desc *c)
{
    int mi;
    if (!c->master_id || !find_control(cam, c->master_id, &mi))
        return 0;
    return control_value(cam, mi) != c->master_manual;
}

static const uint32_t class_ids[] = {V4L2_CID_USER_CLASS, V4L2_CID_CAMERA_CLASS};
static const char *const class_names[] = {"User Controls", "Camera Controls"};

static int class_present(struct camera *cam, int k)
{
    for (uint32_t i = 0; i < cam->n_controls; i++)
        if (V4L2_CTRL_ID2CLASS(cam->controls[i].id) == V4L2_CTRL_ID2CLASS(class_ids[k]))
            return 1;
    return 0;
}

/* Fill a query for id (or the next id after it); 0, or an errno. As the kernel: with
 * V4L2_CTRL_FLAG_NEXT_CTRL alone the next control that is neither an array nor of a compound
 * type, with V4L2_CTRL_FLAG_NEXT_COMPOUND alone the next that is, with both the next one. */
static int query_control(struct camera *cam, uint32_t req, struct v4l2_query_ext_ctrl *q)
{
    uint32_t which = req & (V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND);
    int next = which != 0;
    uint32_t id = req & ~(V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND);
    const struct control_desc *best = NULL;
    int best_class = -1;
    uint32_t best_id = UINT32_MAX;
    for (uint32_t i = 0; i < cam->n_controls; i++) {
        const struct control_desc *c = &cam->controls[i];
        if (which == V4L2_CTRL_FLAG_NEXT_CTRL && is_compound(c))
            continue;
        if (which == V4L2_CTRL_FLAG_NEXT_COMPOUND && !is_compound(c))
            continue;
        if ((!next && c->id == id) || (next && c->id > id && c->id < best_id)) {
            best = c;
            best_id = c->id;
        }
    }
    for (int k = 0; k < 2 && which != V4L2_CTRL_FLAG_NEXT_COMPOUND; k++) {
        if (!class_present(cam, k))
            continue;
        uint32_t cid = class_ids[k];
        if ((!next && cid == id) || (next && cid > id && cid < best_id)) {
            best = NULL;
            best_class = k;
            best_id = cid;
        }
    }
    if (best_id == UINT32_MAX)
        return EINVAL;
    memset(q, 0, sizeof(*q));
    q->id = best_id;
    q->elem_size = 4;
    q->elems = 1;
    if (best_class >= 0) {
        q->type = V4L2_CTRL_TYPE_CTRL_CLASS;
        copy_text(q->name, sizeof(q->name), class_names[best_class]);
        q->flags = V4L2_CTRL_FLAG_READ_ONLY | V4L2_CTRL_FLAG_WRITE_ONLY;
        q->elem_size = 0;
        return 0;
    }
    q->type = best->type;
    copy_text(q->name, sizeof(q->name), best->name);
    q->minimum = best->minimum;
    q->maximum = best->maximum;
    q->step = (uint64_t)best->step;
    q->default_value = best->def;
    q->flags = best->flags;
    if (inactive(cam, best))
        q->flags |= V4L2_CTRL_FLAG_INACTIVE;
    q->elem_size = best->elem_size;
    q->nr_of_dims = best->n_dims;
    for (uint32_t d = 0; d < best->n_dims; d++) {
        q->dims[d] = best->dims[d];
        q->elems *= best->dims[d];
    }
    return 0;
}

static int is_class_id(uint32_t id)
{
    return id == V4L2_CID_USER_CLASS || id == V4L2_CID_CAMERA_CLASS;
}

/* Whether this control may be read or written now (uvcvideo's rules); 0 or an errno. */
static int check_access(struct camera *cam, uint32_t id, int write,
                        const struct v4l2_ext_controls *ctrls)
{
    if (is_class_id(id))
        return EACCES;
    int index;
    const struct control_desc *c = find_control(cam, id, &index);
    if (!c)
        return EINVAL;
    if (write && (c->flags & V4L2_CTRL_FLAG_READ_ONLY))
        return EACCES;
    if (!write && (c->flags & V4L2_CTRL_FLAG_WRITE_ONLY))
        return EACCES;
    if (!write || !c->master_id)
        return 0;
    if (ctrls) {
        for (int i = (int)ctrls->count - 1; i >= 0; i--)
            if (ctrls->controls[i].id == c->master_id)
                return ctrls->controls[i].value == c->master_manual ? 0 : EACCES;
    }
    return inactive(cam, c) ? EACCES : 0;
}

/* Validate and adjust a value as the drivers do: integers clamped to the range and rounded to
 * the step (uvcvideo), a bitmask's bits kept to the mask (the kernel's controls framework). */
static int adjust_value(const struct control_desc *c, int64_t *value)
{
    int64_t v = *value;
    switch (c->type) {
    case V4L2_CTRL_TYPE_INTEGER:
    case V4L2_CTRL_TYPE_INTEGER64:
        if (v < c->minimum)
            v = c->minimum;
        if (v > c->maximum)
            v = c->maximum;
        if (c->step > 1) {
            /* unsigned: a range from INT64_MIN does not overflow */
            uint64_t offset = (uint64_t)v - (uint64_t)c->minimum, step = (uint64_t)c->step;
            v = (int64_t)((uint64_t)c->minimum + (offset + step / 2) / step * step);
            if (v > c->maximum)
                v -= c->step;
        }
        break;
    case V4L2_CTRL_TYPE_BOOLEAN:
        v = v ? 1 : 0;
        break;
    case V4L2_CTRL_TYPE_BITMASK:
        v = (int32_t)((uint32_t)v & (uint32_t)c->maximum);
        break;
    case V4L2_CTRL_TYPE_MENU:
    case V4L2_CTRL_TYPE_INTEGER_MENU: {
        int ok = 0;
        if (v < 0 || v >= 32)
            return ERANGE;
        for (uint32_t i = 0; i < c->n_menu; i++)
            ok |= c->menu[i].index == v;
        if (!ok)
            return EINVAL;
        break;
    }
    default:
        break;
    }
    *value = v;
    return 0;
}

/* Store a value; a button counts the presses instead, for the harness to read. */
static void set_value(struct camera *cam, uint32_t id, int64_t value)
{
    int index;
    const struct control_desc *c = find_control(cam, id, &index);
    if (!c)
        return;
    if (c->type == V4L2_CTRL_TYPE_BUTTON)
        __atomic_fetch_add(&cam->state->values[index], 1, __ATOMIC_ACQ_REL);
    else if (c->type == V4L2_CTRL_TYPE_INTEGER64)
        __atomic_store_n(&cam->state->wide[index], value, __ATOMIC_RELEASE);
    else
        __atomic_store_n(&cam->state->values[index], (int32_t)value, __ATOMIC_RELEASE);
}

/* G/S/TRY_EXT_CTRLS: 32-bit controls in `value`, INTEGER64 in `value64`. The payload of a
 * string, array or compound control is not emulated (EINVAL). */
static int ext_controls(struct handle *h, unsigned int cmd, struct v4l2_ext_controls *ctrls)
{
    struct camera *cam = h->cam;
    int write = cmd != VIDIOC_G_EXT_CTRLS;
    int defaults = ctrls->which == V4L2_CTRL_WHICH_DEF_VAL;
    if (ctrls->count > 64)
        return E2BIG;
    if (defaults && write)
        return EINVAL;
    for (uint32_t i = 0; i < ctrls->count; i++) {
        struct v4l2_ext_control *x = &ctrls->controls[i];
        int err = check_access(cam, x->id, write, write ? ctrls : NULL);
        if (err == EACCES && defaults && !is_class_id(x->id))
            err = 0;
        if (!err && is_pointer(find_control(cam, x->id, NULL)))
            err = EINVAL;
        if (err) {
            ctrls->error_idx = write ? ctrls->count : i;
            return err;
        }
    }
    for (uint32_t i = 0; i < ctrls->count; i++) {
        struct v4l2_ext_control *x = &ctrls->controls[i];
        int index = 0;
        const struct control_desc *c = find_control(cam, x->id, &index);
        int wide = c->type == V4L2_CTRL_TYPE_INTEGER64;
        if (!write) {
            int64_t v = defaults ? c->def : control_value(cam, index);
            if (wide)
                x->value64 = v;
            else
                x->value = (int32_t)v;
            continue;
        }
        int64_t v = wide ? x->value64 : x->value;
        int err = adjust_value(c, &v);
        if (err) {
            ctrls->error_idx = i;
            return err;
        }
        if (wide)
            x->value64 = v;
        else
            x->value = (int32_t)v;
    }
    if (cmd == VIDIOC_S_EXT_CTRLS)
        for (uint32_t i = 0; i < ctrls->count; i++) {
            struct v4l2_ext_control *x = &ctrls->controls[i];
            const struct control_desc *c = find_control(cam, x->id, NULL);
            set_value(cam, x->id, c->type == V4L2_CTRL_TYPE_INTEGER64 ? x->value64 : x->value);
        }
    return 0;
}

static uint32_t find_format(struct camera *cam, uint32_t fourcc, int *ok)
{
    for (uint32_t i = 0; i < cam->n_formats; i++)
        if (cam->formats[i].fourcc == fourcc) {
            *ok = 1;
            return i;
        }
    *ok = 0;
    return 0;
}

static uint32_t nearest_frame(const struct format_desc *fmt, uint32_t w, uint32_t h)
{
    uint64_t best = UINT64_MAX;
    uint32_t pick = 0;
    for (uint32_t i = 0; i < fmt->n_frames; i++) {
        uint64_t fw = fmt->frames[i].width, fh = fmt->frames[i].height;
        uint64_t common = (fw < w ? fw : w) * (fh < h ? fh : h);
        uint64_t d = fw * fh + (uint64_t)w * h - 2 * common;
        if (d < best) {
            best = d;
            pick = i;
        }
    }
    return pick;
}

static double seconds(struct v4l2_fract f)
{
    return f.denominator ? (double)f.numerator / f.denominator : 0.0;
}

static uint32_t nearest_interval(const struct frame_desc *fd, double want)
{
    double best = INFINITY;
    uint32_t pick = 0;
    for (uint32_t i = 0; i < fd->n_intervals; i++) {
        double d = fabs(seconds(fd->intervals[i]) - want);
        if (d < best) {
            best = d;
            pick = i;
        }
    }
    return pick;
}

static void fill_pix(struct camera *cam, uint32_t f, uint32_t fr, struct v4l2_pix_format *pix)
{
    const struct format_desc *fmt = &cam->formats[f];
    const struct frame_desc *fd = &fmt->frames[fr];
    memset(pix, 0, sizeof(*pix));
    pix->width = fd->width;
    pix->height = fd->height;
    pix->pixelformat = fmt->fourcc;
    pix->field = V4L2_FIELD_NONE;
    pix->bytesperline = fd->bytesperline;
    pix->sizeimage = fd->sizeimage;
    pix->colorspace = V4L2_COLORSPACE_SRGB;
}

static struct shared_state *st(struct handle *h)
{
    return h->cam->state;
}

static void current(struct handle *h, uint32_t *f, uint32_t *fr, uint32_t *iv)
{
    struct camera *cam = h->cam;
    *f = __atomic_load_n(&st(h)->cur_format, __ATOMIC_ACQUIRE);
    if (*f >= cam->n_formats)
        *f = 0;
    *fr = __atomic_load_n(&st(h)->cur_frame, __ATOMIC_ACQUIRE);
    if (*fr >= cam->formats[*f].n_frames)
        *fr = 0;
    *iv = __atomic_load_n(&st(h)->cur_interval, __ATOMIC_ACQUIRE);
    if (*iv >= cam->formats[*f].frames[*fr].n_intervals)
        *iv = 0;
}

static int try_format(struct handle *h, struct v4l2_format *f, uint32_t *fi, uint32_t *fri,
                      uint32_t *ivi)
{
    struct camera *cam = h->cam;
    if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE)
        return EINVAL;
    uint32_t cf, cfr, civ;
    current(h, &cf, &cfr, &civ);
    int ok;
    uint32_t fmt = find_format(cam, f->fmt.pix.pixelformat, &ok);
    if (!ok)
        fmt = 0;   /* the default format, as uvcvideo answers an unknown one */
    uint32_t fr = nearest_frame(&cam->formats[fmt], f->fmt.pix.width, f->fmt.pix.height);
    double want = seconds(cam->formats[cf].frames[cfr].intervals[civ]);
    uint32_t iv = nearest_interval(&cam->formats[fmt].frames[fr], want);
    fill_pix(cam, fmt, fr, &f->fmt.pix);
    *fi = fmt;
    *fri = fr;
    *ivi = iv;
    return 0;
}

static int request_buffers(struct handle *h, struct v4l2_requestbuffers *rb)
{
    /* uvcvideo's queue takes MMAP, USERPTR and DMABUF; the emulation MMAP and USERPTR. */
    int user = rb->memory == V4L2_MEMORY_USERPTR;
    if (rb->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || !(rb->memory == V4L2_MEMORY_MMAP
            || (user && h->cam->no_userptr != 1)))
        return EINVAL;
    int err = acquire(h);
    if (err)
        return err;
    if (h->streaming)
        return EBUSY;
    free_buffers(h);
    rb->capabilities = V4L2_BUF_CAP_SUPPORTS_MMAP
        | (h->cam->no_userptr == 1 ? 0 : V4L2_BUF_CAP_SUPPORTS_USERPTR);
    if (rb->count == 0) {
        release_owner(h);
        return 0;
    }
    uint32_t f, fr, iv;
    current(h, &f, &fr, &iv);
    uint32_t count = rb->count > MAX_BUFFERS ? MAX_BUFFERS : rb->count;
    size_t page = (size_t)sysconf(_SC_PAGESIZE);
    size_t size = h->cam->formats[f].frames[fr].sizeimage;
    h->stride = (size + page - 1) / page * page;
    h->memory = rb->memory;
    if (user)
        goto counted;   /* the program brings the memory, buffer by buffer at QBUF */
    h->memfd = memfd_create("uvc-emulator", MFD_CLOEXEC);
    if (h->memfd < 0 || ftruncate(h->memfd, (off_t)(h->stride * count)) != 0) {
        free_buffers(h);
        return ENOMEM;
    }
    h->mem = real_mmap(NULL, h->stride * count, PROT_READ | PROT_WRITE, MAP_SHARED, h->memfd, 0);
    if (h->mem == MAP_FAILED) {
        h->mem = NULL;
        free_buffers(h);
        return ENOMEM;
    }
counted:
    h->n_buffers = count;
    for (uint32_t i = 0; i < count; i++) {
        memset(&h->buffers[i], 0, sizeof(h->buffers[i]));
        h->buffers[i].bg_frame = -1;
    }
    h->fmt = f;
    h->frame = fr;
    h->interval = h->cam->formats[f].frames[fr].intervals[iv];
    rb->count = count;
    return 0;
}

static void fill_buffer(struct handle *h, uint32_t i, struct v4l2_buffer *b)
{
    struct buffer *buf = &h->buffers[i];
    memset(b, 0, sizeof(*b));
    b->index = i;
    b->type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b->memory = h->memory;
    if (h->memory == V4L2_MEMORY_USERPTR) {
        b->m.userptr = (unsigned long)buf->user;
        b->length = (uint32_t)buf->user_length;
    } else {
        b->m.offset = (uint32_t)(i * h->stride);
        b->length = h->cam->formats[h->fmt].frames[h->frame].sizeimage;
    }
    b->field = V4L2_FIELD_NONE;
    b->flags = (h->memory == V4L2_MEMORY_MMAP ? V4L2_BUF_FLAG_MAPPED : 0)
        | V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE;
    if (buf->state == BUF_QUEUED)
        b->flags |= V4L2_BUF_FLAG_QUEUED;
    if (buf->state == BUF_DONE)
        b->flags |= V4L2_BUF_FLAG_DONE;
    if (buf->error)
        b->flags |= V4L2_BUF_FLAG_ERROR;
    b->bytesused = buf->bytesused;
    b->sequence = buf->sequence;
    b->timestamp = buf->timestamp;
}

static int do_ioctl(struct handle *h, unsigned int cmd, void *arg)
{
    struct camera *cam = h->cam;
    if (dead(h)) {
        if (!h->dead) {
            h->dead = 1;
            sync_event(h);
            pthread_cond_broadcast(&h->cond);
        }
        return ENODEV;
    }
    if (!arg && cmd != VIDIOC_LOG_STATUS)
        return EFAULT;
    switch (cmd) {
    case VIDIOC_QUERYCAP: {
        struct v4l2_capability *c = arg;
        memset(c, 0, sizeof(*c));
        copy_text((char *)c->driver, sizeof(c->driver), cam->driver[0] ? cam->driver
                                                                          : "uvcvideo");
        copy_text((char *)c->card, sizeof(c->card), cam->card);
        copy_text((char *)c->bus_info, sizeof(c->bus_info), cam->bus_info);
        c->version = kernel_version;
        c->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING | V4L2_CAP_EXT_PIX_FORMAT;
        c->capabilities = c->device_caps | V4L2_CAP_META_CAPTURE | V4L2_CAP_DEVICE_CAPS;
        return 0;
    }
    case VIDIOC_ENUMINPUT: {
        struct v4l2_input *in = arg;
        if (in->index != 0)
            return EINVAL;
        uint32_t index = in->index;
        memset(in, 0, sizeof(*in));
        in->index = index;
        copy_text((char *)in->name, sizeof(in->name), "Camera 1");
        in->type = V4L2_INPUT_TYPE_CAMERA;
        return 0;
    }
    case VIDIOC_G_INPUT:
        *(int *)arg = 0;
        return 0;
    case VIDIOC_S_INPUT:
        return *(int *)arg == 0 ? 0 : EINVAL;
    case VIDIOC_G_PRIORITY:
        *(uint32_t *)arg = V4L2_PRIORITY_DEFAULT;
        return 0;
    case VIDIOC_S_PRIORITY:
        return 0;
    case VIDIOC_LOG_STATUS:
        return 0;
    case VIDIOC_ENUM_FMT: {
        struct v4l2_fmtdesc *d = arg;
        if (d->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || d->index >= cam->n_formats)
            return EINVAL;
        const struct format_desc *fmt = &cam->formats[d->index];
        uint32_t index = d->index, type = d->type;
        memset(d, 0, sizeof(*d));
        d->index = index;
        d->type = type;
        d->flags = fmt->flags;
        d->pixelformat = fmt->fourcc;
        copy_text((char *)d->description, sizeof(d->description), fmt->description);
        return 0;
    }
    case VIDIOC_ENUM_FRAMESIZES: {
        struct v4l2_frmsizeenum *e = arg;
        int ok;
        uint32_t f = find_format(cam, e->pixel_format, &ok);
        if (!ok || e->index >= cam->formats[f].n_frames)
            return EINVAL;
        const struct frame_desc *fd = &cam->formats[f].frames[e->index];
        memset(&e->type, 0, sizeof(*e) - offsetof(struct v4l2_frmsizeenum, type));
        e->type = V4L2_FRMSIZE_TYPE_DISCRETE;
        e->discrete.width = fd->width;
        e->discrete.height = fd->height;
        return 0;
    }
    case VIDIOC_ENUM_FRAMEINTERVALS: {
        struct v4l2_frmivalenum *e = arg;
        int ok;
        uint32_t f = find_format(cam, e->pixel_format, &ok);
        if (!ok)
            return EINVAL;
        const struct format_desc *fmt = &cam->formats[f];
        for (uint32_t i = 0; i < fmt->n_frames; i++) {
            const struct frame_desc *fd = &fmt->frames[i];
            if (fd->width != e->width || fd->height != e->height)
                continue;
            if (e->index >= fd->n_intervals)
                return EINVAL;
            e->type = V4L2_FRMIVAL_TYPE_DISCRETE;
            memset(e->reserved, 0, sizeof(e->reserved));
            e->discrete = fd->intervals[e->index];
            return 0;
        }
        return EINVAL;
    }
    case VIDIOC_G_FMT: {
        struct v4l2_format *f = arg;
        if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE)
            return EINVAL;
        uint32_t fi, fr, iv;
        current(h, &fi, &fr, &iv);
        fill_pix(cam, fi, fr, &f->fmt.pix);
        return 0;
    }
    case VIDIOC_TRY_FMT: {
        uint32_t fi, fr, iv;
        return try_format(h, arg, &fi, &fr, &iv);
    }
    case VIDIOC_S_FMT: {
        uint32_t fi, fr, iv;
        struct v4l2_format *f = arg;
        if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE)
            return EINVAL;
        int err = acquire(h);
        if (err)
            return err;
        if (h->streaming || h->n_buffers)
            return EBUSY;
        try_format(h, f, &fi, &fr, &iv);
        __atomic_store_n(&st(h)->cur_format, fi, __ATOMIC_RELEASE);
        __atomic_store_n(&st(h)->cur_frame, fr, __ATOMIC_RELEASE);
        __atomic_store_n(&st(h)->cur_interval, iv, __ATOMIC_RELEASE);
        return 0;
    }
    case VIDIOC_G_PARM:
    case VIDIOC_S_PARM: {
        struct v4l2_streamparm *p = arg;
        if (p->type != V4L2_BUF_TYPE_VIDEO_CAPTURE)
            return EINVAL;
        uint32_t fi, fr, iv;
        current(h, &fi, &fr, &iv);
        const struct frame_desc *fd = &cam->formats[fi].frames[fr];
        if (cmd == VIDIOC_S_PARM) {
            int err = acquire(h);
            if (err)
                return err;
            if (h->streaming)
                return EBUSY;
            struct v4l2_fract want = p->parm.capture.timeperframe;
            if (want.numerator && want.denominator)
                iv = nearest_interval(fd, seconds(want));
            __atomic_store_n(&st(h)->cur_interval, iv, __ATOMIC_RELEASE);
            if (h->n_buffers)
                h->interval = fd->intervals[iv];
        }
        memset(&p->parm, 0, sizeof(p->parm));
        p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
        p->parm.capture.timeperframe = fd->intervals[iv];
        return 0;
    }
    case VIDIOC_REQBUFS:
        return request_buffers(h, arg);
    case VIDIOC_QUERYBUF: {
        struct v4l2_buffer *b = arg;
        if (b->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || b->index >= h->n_buffers)
            return EINVAL;
        fill_buffer(h, b->index, b);
        return 0;
    }
    case VIDIOC_QBUF: {
        struct v4l2_buffer *b = arg;
        if (b->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || b->memory != h->memory
                || b->index >= h->n_buffers || !owns(h))
            return EINVAL;
        if (h->buffers[b->index].state != BUF_IDLE)
            return EINVAL;
        if (h->memory == V4L2_MEMORY_USERPTR) {
            /* As vb2: the memory must hold a whole image; another place than the last
             * time holds none of the picture drawn there. */
            struct buffer *buf = &h->buffers[b->index];
            if (!b->m.userptr || b->length < cam->formats[h->fmt].frames[h->frame].sizeimage)
                return EINVAL;
            if (cam->no_userptr == 2)   /* memory the driver cannot use (not contiguous) */
                return EFAULT;
            if (buf->user != (uint8_t *)b->m.userptr)
                buf->bg_frame = -1;   /* (the program is trusted not to write into it) */
            buf->user = (uint8_t *)b->m.userptr;
            buf->user_length = b->length;
        }
        h->buffers[b->index].state = BUF_QUEUED;
        h->queued[h->n_queued++] = b->index;
        fill_buffer(h, b->index, b);
        return 0;
    }
    case VIDIOC_DQBUF: {
        struct v4l2_buffer *b = arg;
        if (b->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || b->memory != h->memory)
            return EINVAL;
        if (h->dead || dead(h))
            return ENODEV;
        if (!h->streaming)
            return EINVAL;
        if (!h->n_done)
            return EAGAIN;
        uint32_t i = h->done[0];
        memmove(h->done, h->done + 1, --h->n_done * sizeof(uint32_t));
        fill_buffer(h, i, b);
        b->flags &= ~(uint32_t)V4L2_BUF_FLAG_DONE;
        if (h->buffers[i].jpeg)
            record_served(h, &h->buffers[i]);
        h->buffers[i].state = BUF_IDLE;
        sync_event(h);
        return 0;
    }
    case VIDIOC_STREAMON: {
        if (*(int *)arg != V4L2_BUF_TYPE_VIDEO_CAPTURE || !h->n_buffers)
            return EINVAL;
        if (cam->streamon_errno)
            return cam->streamon_errno;
        int err = acquire(h);
        if (err)
            return err;
        if (h->streaming)
            return 0;
        err = bus_reserve(h);
        if (err)
            return err;
        h->streaming = 1;
        h->stop = 0;
        h->sequence = 0;
        free(h->scratch);
        h->scratch = NULL;
        if (pthread_create(&h->thread, NULL, producer, h) != 0) {
            h->streaming = 0;
            bus_release(h);
            return ENOMEM;
        }
        sync_event(h);
        return 0;
    }
    case VIDIOC_STREAMOFF:
        if (*(int *)arg != V4L2_BUF_TYPE_VIDEO_CAPTURE)
            return EINVAL;
        if (h->n_buffers && !owns(h))
            return EBUSY;
        stop_streaming(h);
        return 0;
    case VIDIOC_QUERYCTRL: {
        struct v4l2_queryctrl *q = arg;
        struct v4l2_query_ext_ctrl x;
        int err = query_control(cam, q->id, &x);
        if (err)
            return err;
        memset(q, 0, sizeof(*q));
        q->id = x.id;
        q->type = x.type;
        copy_text((char *)q->name, sizeof(q->name), x.name);
        q->flags = x.flags;
        /* as the kernel: no 64-bit or compound range in the old structure */
        if (x.type != V4L2_CTRL_TYPE_INTEGER64 && x.type < V4L2_CTRL_COMPOUND_TYPES &&
            x.type != V4L2_CTRL_TYPE_BUTTON) {
            q->minimum = (int32_t)x.minimum;
            q->maximum = (int32_t)x.maximum;
            q->step = (int32_t)x.step;
            q->default_value = (int32_t)x.default_value;
        }
        return 0;
    }
    case VIDIOC_QUERY_EXT_CTRL:
        return query_control(cam, ((struct v4l2_query_ext_ctrl *)arg)->id, arg);
    case VIDIOC_QUERYMENU: {
        struct v4l2_querymenu *m = arg;
        const struct control_desc *c = find_control(cam, m->id, NULL);
        if (!c || (c->type != V4L2_CTRL_TYPE_MENU && c->type != V4L2_CTRL_TYPE_INTEGER_MENU))
            return EINVAL;
        for (uint32_t i = 0; i < c->n_menu; i++)
            if ((uint32_t)c->menu[i].index == m->index) {
                memset(m->name, 0, sizeof(m->name));
                if (c->type == V4L2_CTRL_TYPE_INTEGER_MENU)
                    m->value = c->menu[i].value;
                else
                    copy_text((char *)m->name, sizeof(m->name), c->menu[i].name);
                m->reserved = 0;
                return 0;
            }
        return EINVAL;
    }
    case VIDIOC_G_CTRL: {
        struct v4l2_control *c = arg;
        const struct control_desc *d = find_control(cam, c->id, NULL);
        if (d && !is_int(d))
            return EINVAL;    /* a 64-bit or pointer control: G_EXT_CTRLS only */
        int err = check_access(cam, c->id, 0, NULL), index = 0;
        if (err)
            return err;
        find_control(cam, c->id, &index);
        c->value = (int32_t)control_value(cam, index);
        return 0;
    }
    case VIDIOC_S_CTRL: {
        struct v4l2_control *c = arg;
        const struct control_desc *d = find_control(cam, c->id, NULL);
        if (d && !is_int(d))
            return EINVAL;    /* a 64-bit or pointer control: S_EXT_CTRLS only */
        int err = check_access(cam, c->id, 1, NULL);
        if (err)
            return err;
        int64_t v = c->value;
        err = adjust_value(d, &v);
        if (err)
            return err;
        c->value = (int32_t)v;
        set_value(cam, c->id, v);
        return 0;
    }
    case VIDIOC_G_EXT_CTRLS:
    case VIDIOC_S_EXT_CTRLS:
    case VIDIOC_TRY_EXT_CTRLS:
        return ext_controls(h, cmd, arg);
    default:
        return ENOTTY;
    }
}

/* Blocking DQBUF for descriptors opened without O_NONBLOCK: wait for a frame. */
static int dqbuf_wait(struct handle *h)
{
    while (!h->n_done && h->streaming && !h->dead && !dead(h)
           && (h->n_queued || h->in_flight)) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += 50 * 1000000;
        if (ts.tv_nsec >= 1000000000) {
            ts.tv_sec++;
            ts.tv_nsec -= 1000000000;
        }
        pthread_cond_timedwait(&h->cond, &h->lock, &ts);
    }
    return 0;
}

/* ------------------------------------------------------------------ libc entry points */

EXPORT int ioctl(int fd, unsigned long request, ...)
{
    va_list ap;
    va_start(ap, request);
    void *arg = va_arg(ap, void *);
    va_end(ap);
    ensure_init();
    struct handle *h = lookup(fd);
    if (!h)
        return real_ioctl(fd, request, arg);
    unsigned int cmd = (unsigned int)request;
    pthread_mutex_lock(&h->lock);
    if (cmd == VIDIOC_DQBUF && h->streaming && !h->nonblock)
        dqbuf_wait(h);
    int err = do_ioctl(h, cmd, arg);
    pthread_mutex_unlock(&h->lock);
    if (err) {
        errno = err;
        return -1;
    }
    return 0;
}

static int open_common(int (*real)(const char *, int, ...), const char *path, int flags,
                       mode_t mode)
{
    ensure_init();
    int fd;
    if (n_cameras && emulated_open(path, flags, &fd))
        return fd;
    return forget_stale(real(path, flags, mode));
}

static mode_t open_mode(int flags, va_list ap)
{
    return (flags & (O_CREAT | __O_TMPFILE)) ? (mode_t)va_arg(ap, int) : 0;
}

EXPORT int open(const char *path, int flags, ...)
{
    va_list ap;
    va_start(ap, flags);
    mode_t mode = open_mode(flags, ap);
    va_end(ap);
    ensure_init();
    return open_common(real_open, path, flags, mode);
}

EXPORT int open64(const char *path, int flags, ...)
{
    va_list ap;
    va_start(ap, flags);
    mode_t mode = open_mode(flags, ap);
    va_end(ap);
    ensure_init();
    return open_common(real_open64 ? real_open64 : real_open, path, flags, mode);
}

EXPORT int __open_2(const char *path, int flags)
{
    ensure_init();
    return open_common(real_open, path, flags, 0);
}

EXPORT int __open64_2(const char *path, int flags)
{
    ensure_init();
    return open_common(real_open64 ? real_open64 : real_open, path, flags, 0);
}

static int openat_common(int (*real)(int, const char *, int, ...), int dirfd, const char *path,
                         int flags, mode_t mode)
{
    ensure_init();
    int fd;
    if (n_cameras && path && path[0] == '/' && emulated_open(path, flags, &fd))
        return fd;
    return forget_stale(real(dirfd, path, flags, mode));
}

EXPORT int openat(int dirfd, const char *path, int flags, ...)
{
    va_list ap;
    va_start(ap, flags);
    mode_t mode = open_mode(flags, ap);
    va_end(ap);
    ensure_init();
    return openat_common(real_openat, dirfd, path, flags, mode);
}

EXPORT int openat64(int dirfd, const char *path, int flags, ...)
{
    va_list ap;
    va_start(ap, flags);
    mode_t mode = open_mode(flags, ap);
    va_end(ap);
    ensure_init();
    return openat_common(real_openat64 ? real_openat64 : real_openat, dirfd, path, flags, mode);
}

EXPORT int __openat_2(int dirfd, const char *path, int flags)
{
    ensure_init();
    return openat_common(real_openat, dirfd, path, flags, 0);
}

EXPORT int __openat64_2(int dirfd, const char *path, int flags)
{
    ensure_init();
    return openat_common(real_openat64 ? real_openat64 : real_openat, dirfd, path, flags, 0);
}

/* Forget descriptor fd of a handle; the last one stops streaming and frees the buffers. */
static void drop_descriptor(int fd, struct handle *h)
{
    pthread_mutex_lock(&table_lock);
    handles[fd] = NULL;
    int last = --h->refs == 0;
    pthread_mutex_unlock(&table_lock);
    if (!last)
        return;
    pthread_mutex_lock(&h->lock);
    stop_streaming(h);
    if (!h->forked) {
        free_buffers(h);
        release_owner(h);
    }
    pthread_mutex_unlock(&h->lock);
    if (h->efd >= 0)
        real_close(h->efd);
    free(h);
}

EXPORT int close(int fd)
{
    ensure_init();
    struct handle *h = lookup(fd);
    if (h)
        drop_descriptor(fd, h);
    return real_close(fd);
}

/* A duplicate of an emulated descriptor is the same open device. */
static int adopt_duplicate(struct handle *h, int newfd)
{
    if (!h || newfd < 0)
        return newfd;
    if (newfd >= MAX_FDS) {
        real_close(newfd);
        errno = EMFILE;
        return -1;
    }
    pthread_mutex_lock(&table_lock);
    struct handle *old = handles[newfd];
    if (old && old != h) {
        handles[newfd] = NULL;
        if (--old->refs == 0 && !old->streaming) {
            free_buffers(old);
            release_owner(old);
            if (old->efd >= 0)
                real_close(old->efd);
            free(old);
        }
    }
    if (handles[newfd] != h) {
        handles[newfd] = h;
        h->refs++;
    }
    pthread_mutex_unlock(&table_lock);
    return newfd;
}

EXPORT int dup(int fd)
{
    ensure_init();
    struct handle *h = lookup(fd);
    return adopt_duplicate(h, h ? real_dup(fd) : forget_stale(real_dup(fd)));
}

EXPORT int dup2(int fd, int newfd)
{
    ensure_init();
    struct handle *h = lookup(fd);
    if (fd == newfd)
        return real_dup2(fd, newfd);
    struct handle *target = lookup(newfd);
    if (target && target != h)
        drop_descriptor(newfd, target);
    int r = real_dup2(fd, newfd);
    return h ? adopt_duplicate(h, r) : forget_stale(r);
}

EXPORT int dup3(int fd, int newfd, int flags)
{
    ensure_init();
    struct handle *h = lookup(fd);
    struct handle *target = fd != newfd ? lookup(newfd) : NULL;
    if (target && target != h)
        drop_descriptor(newfd, target);
    int r = real_dup3(fd, newfd, flags);
    return h ? adopt_duplicate(h, r) : forget_stale(r);
}

static int fcntl_common(int fd, int cmd, va_list ap)
{
    ensure_init();
    switch (cmd) {
    case F_DUPFD:
    case F_DUPFD_CLOEXEC: {
        int arg = va_arg(ap, int);
        struct handle *h = lookup(fd);
        int r = real_fcntl(fd, cmd, arg);
        return h ? adopt_duplicate(h, r) : forget_stale(r);
    }
    case F_GETFD:
    case F_GETFL:
    case F_GETOWN:
    case F_GETSIG:
    case F_GETLEASE:
    case F_GETPIPE_SZ:
    case F_GET_SEALS:
        return real_fcntl(fd, cmd);
    case F_SETFL: {
        int arg = va_arg(ap, int);
        struct handle *h = lookup(fd);
        if (h) {
            pthread_mutex_lock(&h->lock);
            h->nonblock = (arg & O_NONBLOCK) != 0;
            pthread_mutex_unlock(&h->lock);
            arg |= O_NONBLOCK;   /* the eventfd itself stays non-blocking */
        }
        return real_fcntl(fd, cmd, arg);
    }
    default: {
        void *arg = va_arg(ap, void *);
        return real_fcntl(fd, cmd, arg);
    }
    }
}

EXPORT int fcntl(int fd, int cmd, ...)
{
    va_list ap;
    va_start(ap, cmd);
    int r = fcntl_common(fd, cmd, ap);
    va_end(ap);
    return r;
}

EXPORT int fcntl64(int fd, int cmd, ...)
{
    va_list ap;
    va_start(ap, cmd);
    int r = fcntl_common(fd, cmd, ap);
    va_end(ap);
    return r;
}

static void *map_common(void *addr, size_t len, int prot, int flags, int fd, off_t off,
                        int *handled)
{
    struct handle *h = lookup(fd);
    *handled = h != NULL;
    if (!h)
        return NULL;
    pthread_mutex_lock(&h->lock);
    void *result = MAP_FAILED;
    int err = 0;
    if (h->dead || dead(h)) {
        err = ENODEV;
    } else if (!h->mem || off < 0 || (size_t)off % h->stride
               || (size_t)off / h->stride >= h->n_buffers || len > h->stride) {
        err = EINVAL;
    } else if (!(flags & MAP_SHARED)) {
        err = EINVAL;
    } else {
        result = real_mmap(addr, len, prot, flags, h->memfd, off);
        if (result == MAP_FAILED)
            err = errno;
    }
    pthread_mutex_unlock(&h->lock);
    if (err)
        errno = err;
    return result;
}

EXPORT void *mmap(void *addr, size_t len, int prot, int flags, int fd, off_t off)
{
    ensure_init();
    int handled;
    void *r = map_common(addr, len, prot, flags, fd, off, &handled);
    return handled ? r : real_mmap(addr, len, prot, flags, fd, off);
}

EXPORT void *mmap64(void *addr, size_t len, int prot, int flags, int fd, off64_t off)
{
    ensure_init();
    int handled;
    void *r = map_common(addr, len, prot, flags, fd, (off_t)off, &handled);
    if (handled)
        return r;
    return real_mmap64 ? real_mmap64(addr, len, prot, flags, fd, off)
        : real_mmap(addr, len, prot, flags, fd, (off_t)off);
}

/* After a real poll: what a V4L2 device reports for each emulated descriptor. */
static int fix_revents(struct pollfd *fds, nfds_t n, int ready)
{
    if (ready < 0 || !n_cameras)
        return ready;
    int count = 0;
    for (nfds_t i = 0; i < n; i++) {
        struct handle *h = fds[i].fd >= 0 ? lookup(fds[i].fd) : NULL;
        if (h && fds[i].revents) {
            pthread_mutex_lock(&h->lock);
            if (!h->dead && dead(h)) {
                h->dead = 1;
                sync_event(h);
            }
            if (h->dead)
                fds[i].revents = POLLERR | POLLHUP;
            else if (!h->streaming)
                fds[i].revents = POLLERR;
            else if (h->n_done)
                fds[i].revents = fds[i].events & (POLLIN | POLLRDNORM);
            else
                fds[i].revents = 0;
            pthread_mutex_unlock(&h->lock);
        }
        count += fds[i].revents != 0;
    }
    return count;
}

EXPORT int poll(struct pollfd *fds, nfds_t n, int timeout)
{
    ensure_init();
    if (!n_cameras)
        return real_poll(fds, n, timeout);
    struct timespec end;
    clock_gettime(CLOCK_MONOTONIC, &end);
    for (;;) {
        int r = fix_revents(fds, n, real_poll(fds, n, timeout));
        if (r != 0 || timeout == 0)
            return r;
        /* only spurious readiness was dropped: wait out the rest of the timeout */
        if (timeout > 0) {
            struct timespec now;
            clock_gettime(CLOCK_MONOTONIC, &now);
            long spent = (now.tv_sec - end.tv_sec) * 1000 + (now.tv_nsec - end.tv_nsec) / 1000000;
            if (spent >= timeout)
                return 0;
            timeout -= (int)spent;
            end = now;
        }
    }
}

EXPORT int __poll_chk(struct pollfd *fds, nfds_t n, int timeout, size_t size)
{
    (void)size;
    return poll(fds, n, timeout);
}

EXPORT int ppoll(struct pollfd *fds, nfds_t n, const struct timespec *timeout,
                 const sigset_t *sigmask)
{
    ensure_init();
    return fix_revents(fds, n, real_ppoll(fds, n, timeout, sigmask));
}

EXPORT ssize_t read(int fd, void *buf, size_t count)
{
    ensure_init();
    struct handle *h = lookup(fd);
    if (!h)
        return real_read(fd, buf, count);
    errno = dead(h) ? ENODEV : EINVAL;   /* uvcvideo has no read() I/O */
    return -1;
}

/* ---- stat and friends */

static int stat_path(const char *path, struct stat *out, int follow, int *handled)
{
    struct camera *cam;
    int kind = n_cameras ? match_path(path, &cam) : PATH_NONE;
    *handled = kind != PATH_NONE;
    if (!*handled)
        return 0;
    fill_stat(cam, follow && kind == PATH_LINK ? PATH_DEVICE : kind, out);
    return 0;
}

static int stat_fd(int fd, struct stat *out, int *handled)
{
    struct handle *h = lookup(fd);
    *handled = h != NULL;
    if (h)
        fill_stat(h->cam, PATH_DEVICE, out);
    return 0;
}

EXPORT int stat(const char *path, struct stat *out)
{
    ensure_init();
    int handled, r = stat_path(path, out, 1, &handled);
    return handled ? r : real_stat(path, out);
}

EXPORT int stat64(const char *path, struct stat64 *out)
{
    return stat(path, (struct stat *)out);
}

EXPORT int lstat(const char *path, struct stat *out)
{
    ensure_init();
    int handled, r = stat_path(path, out, 0, &handled);
    return handled ? r : real_lstat(path, out);
}

EXPORT int lstat64(const char *path, struct stat64 *out)
{
    return lstat(path, (struct stat *)out);
}

EXPORT int fstat(int fd, struct stat *out)
{
    ensure_init();
    int handled, r = stat_fd(fd, out, &handled);
    return handled ? r : real_fstat(fd, out);
}

EXPORT int fstat64(int fd, struct stat64 *out)
{
    return fstat(fd, (struct stat *)out);
}

EXPORT int fstatat(int dirfd, const char *path, struct stat *out, int flags)
{
    ensure_init();
    int handled = 0, r = 0;
    if (path && path[0] == '/')
        r = stat_path(path, out, !(flags & AT_SYMLINK_NOFOLLOW), &handled);
    else if (path && !path[0] && (flags & AT_EMPTY_PATH))
        r = stat_fd(dirfd, out, &handled);
    return handled ? r : real_fstatat(dirfd, path, out, flags);
}

EXPORT int fstatat64(int dirfd, const char *path, struct stat64 *out, int flags)
{
    return fstatat(dirfd, path, (struct stat *)out, flags);
}

EXPORT int __xstat(int ver, const char *path, struct stat *out)
{
    ensure_init();
    int handled, r = stat_path(path, out, 1, &handled);
    return handled ? r : real_xstat(ver, path, out);
}

EXPORT int __xstat64(int ver, const char *path, struct stat64 *out)
{
    return __xstat(ver, path, (struct stat *)out);
}

EXPORT int __lxstat(int ver, const char *path, struct stat *out)
{
    ensure_init();
    int handled, r = stat_path(path, out, 0, &handled);
    return handled ? r : real_lxstat(ver, path, out);
}

EXPORT int __lxstat64(int ver, const char *path, struct stat64 *out)
{
    return __lxstat(ver, path, (struct stat *)out);
}

EXPORT int __fxstat(int ver, int fd, struct stat *out)
{
    ensure_init();
    int handled, r = stat_fd(fd, out, &handled);
    return handled ? r : real_fxstat(ver, fd, out);
}

EXPORT int __fxstat64(int ver, int fd, struct stat64 *out)
{
    return __fxstat(ver, fd, (struct stat *)out);
}

EXPORT int __fxstatat(int ver, int dirfd, const char *path, struct stat *out, int flags)
{
    ensure_init();
    int handled = 0, r = 0;
    if (path && path[0] == '/')
        r = stat_path(path, out, !(flags & AT_SYMLINK_NOFOLLOW), &handled);
    return handled ? r : real_fxstatat(ver, dirfd, path, out, flags);
}

EXPORT int __fxstatat64(int ver, int dirfd, const char *path, struct stat64 *out, int flags)
{
    return __fxstatat(ver, dirfd, path, (struct stat *)out, flags);
}

EXPORT int statx(int dirfd, const char *path, int flags, unsigned int mask, struct statx *out)
{
    ensure_init();
    struct camera *cam = NULL;
    int kind = PATH_NONE;
    if (n_cameras && path && path[0] == '/') {
        kind = match_path(path, &cam);
        if (kind == PATH_LINK && !(flags & AT_SYMLINK_NOFOLLOW))
            kind = PATH_DEVICE;
    } else if (n_cameras && path && !path[0] && (flags & AT_EMPTY_PATH)) {
        struct handle *h = lookup(dirfd);
        if (h) {
            cam = h->cam;
            kind = PATH_DEVICE;
        }
    }
    if (kind != PATH_NONE) {
        fill_statx(cam, kind, out);
        return 0;
    }
    if (!real_statx) {
        errno = ENOSYS;
        return -1;
    }
    return real_statx(dirfd, path, flags, mask, out);
}

static int access_check(const char *path, int mode, int follow, int *handled)
{
    struct camera *cam;
    int kind = n_cameras ? match_path(path, &cam) : PATH_NONE;
    *handled = kind != PATH_NONE;
    if (!*handled)
        return 0;
    if ((kind == PATH_DEVICE || follow) && (mode & (R_OK | W_OK))
            && __atomic_load_n(&cam->state->denied, __ATOMIC_ACQUIRE)) {
        errno = EACCES;
        return -1;
    }
    if (kind == PATH_DIR)
        return 0;
    if ((kind == PATH_DEVICE || follow) && (mode & X_OK)) {
        errno = EACCES;
        return -1;
    }
    return 0;
}

EXPORT int access(const char *path, int mode)
{
    ensure_init();
    int handled, r = access_check(path, mode, 1, &handled);
    return handled ? r : real_access(path, mode);
}

EXPORT int faccessat(int dirfd, const char *path, int mode, int flags)
{
    ensure_init();
    int handled = 0, r = 0;
    if (path && path[0] == '/')
        r = access_check(path, mode, !(flags & AT_SYMLINK_NOFOLLOW), &handled);
    return handled ? r : real_faccessat(dirfd, path, mode, flags);
}

static ssize_t link_read(const char *path, char *buf, size_t size, int *handled)
{
    struct camera *cam;
    int kind = n_cameras ? match_path(path, &cam) : PATH_NONE;
    *handled = kind != PATH_NONE;
    if (!*handled)
        return 0;
    if (kind != PATH_LINK) {
        errno = EINVAL;
        return -1;
    }
    char target[64];
    link_target(cam, target, sizeof(target));
    size_t n = strlen(target);
    if (n > size)
        n = size;
    memcpy(buf, target, n);
    return (ssize_t)n;
}

EXPORT ssize_t readlink(const char *path, char *buf, size_t size)
{
    ensure_init();
    int handled;
    ssize_t r = link_read(path, buf, size, &handled);
    return handled ? r : real_readlink(path, buf, size);
}

EXPORT ssize_t readlinkat(int dirfd, const char *path, char *buf, size_t size)
{
    ensure_init();
    int handled = 0;
    ssize_t r = 0;
    if (path && path[0] == '/')
        r = link_read(path, buf, size, &handled);
    return handled ? r : real_readlinkat(dirfd, path, buf, size);
}

EXPORT char *realpath(const char *path, char *resolved)
{
    ensure_init();
    struct camera *cam;
    int kind = n_cameras ? match_path(path, &cam) : PATH_NONE;
    if (kind == PATH_DIR) {
        char dir[64];
        int which = link_dir(path);
        copy_text(dir, sizeof(dir), which == 1 ? "/dev/v4l" : which == 2 ? "/dev/v4l/by-id"
                  : "/dev/v4l/by-path");
        if (!resolved)
            return strdup(dir);
        copy_text(resolved, PATH_MAX, dir);
        return resolved;
    }
    if (kind != PATH_NONE) {
        char dev[64];
        device_path(cam, dev, sizeof(dev));
        if (!resolved)
            return strdup(dev);
        copy_text(resolved, PATH_MAX, dev);
        return resolved;
    }
    return real_realpath(path, resolved);
}

EXPORT char *canonicalize_file_name(const char *path)
{
    return realpath(path, NULL);
}

/* ---- directory listings: /dev gets the video nodes, /dev/v4l/by-* the links */

#define MAX_LISTINGS 16

struct listing {
    DIR *dir;
    int which;               /* 0 /dev, 1 /dev/v4l, 2 by-id, 3 by-path */
    int real;                /* the directory exists for real */
    int next;                /* next made-up entry */
    struct dirent64 entry;
};

static struct listing listings[MAX_LISTINGS];
static pthread_mutex_t listing_lock = PTHREAD_MUTEX_INITIALIZER;

static int dev_dir(const char *path)
{
    return !strcmp(path, "/dev") || !strcmp(path, "/dev/");
}

EXPORT DIR *opendir(const char *path)
{
    ensure_init();
    int which = -1;
    struct camera *cam = NULL;
    if (n_cameras && path) {
        if (dev_dir(path))
            which = 0;
        else if (match_path(path, &cam) == PATH_DIR)
            which = link_dir(path);
    }
    DIR *dir = real_opendir(path);
    int real = dir != NULL;
    if (which < 0)
        return dir;
    if (!dir) {
        /* udev's directory does not exist here: list an empty one and add the links */
        char empty[PATH_MAX + 16];
        snprintf(empty, sizeof(empty), "%s/empty", cameras[0]->dir);
        dir = real_opendir(empty);
        if (!dir)
            return NULL;
    }
    pthread_mutex_lock(&listing_lock);
    for (int i = 0; i < MAX_LISTINGS; i++)
        if (!listings[i].dir) {
            memset(&listings[i], 0, sizeof(listings[i]));
            listings[i].dir = dir;
            listings[i].which = which;
            listings[i].real = real;
            break;
        }
    pthread_mutex_unlock(&listing_lock);
    return dir;
}

/* The k-th made-up entry of a listing, or 0 when there are no more. */
static int made_up(struct listing *l, int k, char *name, size_t size, unsigned char *type)
{
    int seen = 0;
    if (l->which == 1) {
        if (l->real)
            return 0;
        if (k > 1)
            return 0;
        copy_text(name, size, k == 0 ? "by-id" : "by-path");
        *type = DT_DIR;
        return 1;
    }
    for (int i = 0; i < n_cameras; i++) {
        struct camera *cam = cameras[i];
        if (!plugged(cam))
            continue;
        /* A device udev made no such link for (by-id: not a USB device) is not listed. */
        if (l->which != 0 && !(l->which == 2 ? cam->by_id : cam->by_path)[0])
            continue;
        if (seen++ != k)
            continue;
        if (l->which == 0) {
            snprintf(name, size, "video%d", __atomic_load_n(&cam->state->node, __ATOMIC_ACQUIRE));
            *type = DT_CHR;
        } else {
            const char *link = l->which == 2 ? cam->by_id : cam->by_path;
            const char *base = strrchr(link, '/');
            copy_text(name, size, base ? base + 1 : link);
            *type = DT_LNK;
        }
        return 1;
    }
    return 0;
}

static struct listing *listing_of(DIR *dir)
{
    for (int i = 0; i < MAX_LISTINGS; i++)
        if (listings[i].dir == dir)
            return &listings[i];
    return NULL;
}

static struct dirent64 *next_made_up(DIR *dir)
{
    pthread_mutex_lock(&listing_lock);
    struct listing *l = listing_of(dir);
    struct dirent64 *result = NULL;
    if (l) {
        unsigned char type = DT_UNKNOWN;
        memset(&l->entry, 0, sizeof(l->entry));
        if (made_up(l, l->next, l->entry.d_name, sizeof(l->entry.d_name), &type)) {
            l->next++;
            l->entry.d_type = type;
            l->entry.d_ino = 0x7c000 + (ino64_t)l->next;
            l->entry.d_reclen = sizeof(l->entry);
            result = &l->entry;
        }
    }
    pthread_mutex_unlock(&listing_lock);
    return result;
}

EXPORT struct dirent *readdir(DIR *dir)
{
    ensure_init();
    struct dirent *entry = real_readdir(dir);
    if (entry || !n_cameras)
        return entry;
    return (struct dirent *)next_made_up(dir);
}

EXPORT struct dirent64 *readdir64(DIR *dir)
{
    ensure_init();
    struct dirent64 *entry = real_readdir64 ? real_readdir64(dir)
        : (struct dirent64 *)real_readdir(dir);
    if (entry || !n_cameras)
        return entry;
    return next_made_up(dir);
}

EXPORT int closedir(DIR *dir)
{
    ensure_init();
    if (n_cameras) {
        pthread_mutex_lock(&listing_lock);
        struct listing *l = listing_of(dir);
        if (l)
            l->dir = NULL;
        pthread_mutex_unlock(&listing_lock);
    }
    return real_closedir(dir);
}

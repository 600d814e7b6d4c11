/* hal_socketcan.c - SocketCAN backend of the Linux host HAL; see hal_socketcan.h. */
#include "hal_socketcan.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

static uint32_t sat_inc(uint32_t n)
{
    return n == UINT32_MAX ? n : n + 1u;
}

uint64_t hal_socketcan_time_us(void)
{
    /* the same clock as SO_TIMESTAMP, so frame and poll times compare */
    struct timespec ts = {0, 0};
    if (clock_gettime(CLOCK_REALTIME, &ts) != 0 || ts.tv_sec < 0) {
        return 0u; /* no clock: never an indeterminate value */
    }
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

int hal_socketcan_open(hal_t *hal, const char *ifname, const uint32_t *rx_ids, size_t n_ids,
                       const char *tx_log_path, const char *nvm_path)
{
    if (hal == NULL || ifname == NULL || strlen(ifname) >= IFNAMSIZ ||
        n_ids > HAL_SOCKETCAN_MAX_FILTERS || (n_ids > 0u && rx_ids == NULL)) {
        return HAL_EINVAL;
    }
    int rc = hal_linux_open(hal, NULL, tx_log_path, nvm_path);
    if (rc != 0) {
        return rc;
    }
    hal_linux_set_iface(hal, ifname);
    const unsigned idx = if_nametoindex(ifname);
    if (idx == 0u) {
        hal_linux_close(hal); /* errno: ENODEV */
        return HAL_EIO;
    }
    const int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        hal_linux_close(hal);
        return HAL_EIO;
    }
    struct can_filter filters[HAL_SOCKETCAN_MAX_FILTERS];
    for (size_t i = 0u; i < n_ids; i++) {
        filters[i].can_id = rx_ids[i] & CAN_SFF_MASK;
        filters[i].can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_SFF_MASK;
    }
    const can_err_mask_t err_mask = CAN_ERR_MASK;
    const int one = 1;
    /* a large receive buffer: a replay faster than real time must not overflow it while
     * the firmware is busy with one frame (FORCE needs root; fall back to the capped one) */
    const int rcvbuf = 4 * 1024 * 1024;
    if (setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) != 0) {
        (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    }
    /* the queue's drop count with each frame (CntRxLost): a count, not a need, so a
     * kernel without it still gives the bus */
    (void)setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)idx;
    if ((n_ids > 0u && setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters,
                                  (socklen_t)(n_ids * sizeof filters[0])) != 0) ||
        setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0 ||
        setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one) != 0 ||
        bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
        const int e = errno;
        close(fd);
        hal_linux_close(hal);
        errno = e;
        return HAL_EIO;
    }
    hal->can_fd = fd;
    hal->rx_log.t_us = hal_socketcan_time_us();
    return 0;
}

int hal_socketcan_wait(hal_t *hal, int timeout_ms)
{
    struct pollfd p = {hal->can_fd, POLLIN, 0};
    const int r = poll(&p, 1u, timeout_ms);
    if (r < 0) {
        return errno == EINTR ? 0 : HAL_EIO;
    }
    return r > 0 ? 1 : 0;
}

int hal_socketcan_receive(hal_t *hal, hal_can_frame_t *f)
{
    for (;;) {
        struct can_frame cf;
        struct iovec iov = {&cf, sizeof cf};
        union {
            char buf[CMSG_SPACE(sizeof(struct timeval)) + CMSG_SPACE(sizeof(uint32_t))];
            struct cmsghdr align;
        } ctrl;
        struct msghdr msg;
        memset(&msg, 0, sizeof msg);
        msg.msg_iov = &iov;
        msg.msg_iovlen = 1u;
        msg.msg_control = ctrl.buf;
        msg.msg_controllen = sizeof ctrl.buf;
        const ssize_t n = recvmsg(hal->can_fd, &msg, 0);
        if (n < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
                return HAL_EAGAIN;
            }
            hal->can_io_errors = sat_inc(hal->can_io_errors); /* ENETDOWN and the like */
            return HAL_EAGAIN;
        }
        if ((size_t)n != sizeof cf) {
            hal->rx_log.malformed = sat_inc(hal->rx_log.malformed); /* not a classic frame */
            continue;
        }
        if (cf.can_id & CAN_ERR_FLAG) {
            /* the controller's report (linux/can/error.h), not a frame lost */
            hal->can_error_frames = sat_inc(hal->can_error_frames);
            if (cf.can_id & CAN_ERR_BUSOFF) {
                hal->can_bus_off++;
            }
            if ((cf.can_id & CAN_ERR_CRTL) && (cf.data[1] & CAN_ERR_CRTL_RX_OVERFLOW)) {
                hal->can_rx_overflow = sat_inc(hal->can_rx_overflow); /* its FIFO: >= 1 lost */
            }
            continue;
        }
        if ((cf.can_id & CAN_RTR_FLAG) || cf.can_dlc > 8u) {
            hal->rx_log.malformed = sat_inc(hal->rx_log.malformed);
            continue;
        }
        uint64_t t = hal_socketcan_time_us();
        for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c != NULL; c = CMSG_NXTHDR(&msg, c)) {
            if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMP &&
                c->cmsg_len >= CMSG_LEN(sizeof(struct timeval))) {
                struct timeval tv;
                memcpy(&tv, CMSG_DATA(c), sizeof tv);
                t = (uint64_t)tv.tv_sec * 1000000u + (uint64_t)tv.tv_usec;
            } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL &&
                       c->cmsg_len >= CMSG_LEN(sizeof(uint32_t))) {
                /* frames the socket's queue dropped since it opened (wraps at 2^32) */
                memcpy(&hal->can_rx_dropped, CMSG_DATA(c), sizeof hal->can_rx_dropped);
            } else {
                /* no other control message is asked for */
            }
        }
        memset(f, 0, sizeof *f);
        f->extended = (uint8_t)((cf.can_id & CAN_EFF_FLAG) ? 1u : 0u);
        f->id = cf.can_id & (f->extended ? CAN_EFF_MASK : CAN_SFF_MASK);
        f->dlc = cf.can_dlc;
        memcpy(f->data, cf.data, cf.can_dlc);
        f->t_us = t;
        hal->rx_log.t_us = t;
        hal->rx_log.frames = sat_inc(hal->rx_log.frames);
        return 0;
    }
}

int hal_socketcan_send(hal_t *hal, const hal_can_frame_t *f)
{
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = f->id | (f->extended ? CAN_EFF_FLAG : 0u);
    cf.can_dlc = f->dlc;
    memcpy(cf.data, f->data, f->dlc);
    const ssize_t n = write(hal->can_fd, &cf, sizeof cf);
    if (n != (ssize_t)sizeof cf) {
        hal->can_io_errors = sat_inc(hal->can_io_errors);
        /* errno only means something when write failed (a short write leaves it stale) */
        return (n < 0 && (errno == ENOBUFS || errno == EAGAIN)) ? HAL_ENOSPC : HAL_EIO;
    }
    return 0;
}

void hal_socketcan_close(hal_t *hal)
{
    if (hal->can_fd >= 0) {
        close(hal->can_fd);
        hal->can_fd = -1;
    }
}

uint32_t hal_socketcan_error_frames(const hal_t *hal)
{
    return hal->can_error_frames;
}

uint32_t hal_socketcan_rx_dropped(const hal_t *hal)
{
    return hal->can_rx_dropped;
}

uint32_t hal_socketcan_io_errors(const hal_t *hal)
{
    return hal->can_io_errors;
}

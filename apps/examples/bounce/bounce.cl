/*
 * bounce.cl: the kernel of the bounce example, one pass of a multipass loop.
 *
 * Particles fly in a two-dimensional box under gravity, in integer units so
 * that the device and the plain C check in main.c agree to the last bit. The
 * floor has a hole: a particle that falls through it has escaped. Every
 * bounce on the rest of the floor takes a quarter of the particle's vertical
 * speed; once that speed is below STOP_SPEED the particle comes to rest and
 * leaves the simulation too. A pass advances each live particle by `steps`
 * time steps and emits
 *   slot 0 (next):      the particles still moving, to be moved in the next pass
 *   slot 1 (departed):  the particles that escaped or stopped, stamped with the
 *                       pass and their fate
 * and counts the escaped and stopped particles with counters 0 and 1.
 *
 * The same constants and the same step function are in main.c.
 */
#include "sluice.cl"

#define BOX_WIDTH 1000000
#define GRAVITY 1000
#define HOLE_BEGIN 400000 /* the hole spans [HOLE_BEGIN, HOLE_END) on the floor */
#define HOLE_END 600000
#define STOP_SPEED 2000

#define FATE_MOVING 0u
#define FATE_ESCAPED 1u
#define FATE_STOPPED 2u

/* One record of the streams: 24 bytes, the same layout as in main.c. */
typedef struct particle {
    int x, y;   /* position, y = 0 is the floor */
    int vx, vy; /* velocity per step */
    uint id;    /* index in the initial stream */
    uint fate;  /* FATE_* in the low byte, the pass it left in above it */
} particle;

/* One time step; returns the particle's fate after it. */
inline uint step(particle *p)
{
    p->vy -= GRAVITY;
    p->x += p->vx;
    p->y += p->vy;
    if (p->x < 0) { /* side walls: mirror */
        p->x = -p->x;
        p->vx = -p->vx;
    } else if (p->x >= BOX_WIDTH) {
        p->x = 2 * (BOX_WIDTH - 1) - p->x;
        p->vx = -p->vx;
    }
    if (p->y < 0) {
        if (p->x >= HOLE_BEGIN && p->x < HOLE_END)
            return FATE_ESCAPED;
        p->y = 0;               /* back on the floor */
        p->vy = -p->vy * 3 / 4; /* the floor takes a quarter of the speed */
        if (p->vy < STOP_SPEED) {
            p->vy = 0;
            return FATE_STOPPED;
        }
    }
    return FATE_MOVING;
}

__kernel void bounce(SLUICE_PARAMS,               /* hidden parameters, always first */
                     global const particle *live, /* argument 0: the input stream */
                     global particle *next,       /* argument 1: output slot 0 */
                     global particle *departed,   /* argument 2: output slot 1 */
                     int steps,                   /* argument 3 */
                     uint pass)                   /* argument 4 */
{
    SLUICE_FOR_EACH (i) {
        /* This body runs twice per particle (count pass, write pass): it only
         * reads the input and its arguments, so both runs emit the same. */
        particle p = live[i];
        uint fate = FATE_MOVING;
        for (int s = 0; s < steps && fate == FATE_MOVING; ++s)
            fate = step(&p);
        p.fate = fate | (pass << 8);

        SLUICE_EMIT_IF(0, next, p, fate == FATE_MOVING);
        SLUICE_EMIT_IF(1, departed, p, fate != FATE_MOVING);
        SLUICE_COUNT(0, fate == FATE_ESCAPED);
        SLUICE_COUNT(1, fate == FATE_STOPPED);
    }
}

/* The number of assimp scenes imported and not yet released (live_scenes.c). */
#ifndef SLUICE_FUZZ_LIVE_SCENES_H
#define SLUICE_FUZZ_LIVE_SCENES_H

extern long fuzz_live_scenes;

#endif

/* The examples' near-field luminaire: a synthetic scan (docs/synthetic.md) generated on first use
 * with the lumiview command-line tool and cached, plus the names of the selection modes. */
#ifndef LV_SCAN_H
#define LV_SCAN_H

#include <stdbool.h>
#include <stdint.h>

#include "lumiview.h"

/* The bundled scan: the synthetic `two-planes` luminaire — 5 × 5 opaque tiles of 30 mm (checkerboard
 * 3,000 / 1,200 cd/m²) in z = 0 in front of a striped back plane at z = +50 mm (6,000 / 2,000 cd/m²),
 * 200 × 200 mm, emitting towards −Z of its frame — captured on `rigo` with 1,000 cameras per
 * hemisphere at 256 × 256 px (capture radius 1.117 m), with its proxy mesh (the tiles and the back
 * plane). */
#define LV_SCAN_LUMINAIRE "two-planes"
#define LV_SCAN_LAYOUT "rigo:1000"
#define LV_SCAN_SIZE "256x256"
/* Ground truth every check uses: the luminaire frame's origin lies on the centre tile (i = j = 2, i + j
 * even: 3,000 cd/m²), which is opaque and in front of everything else, so from any direction with
 * γ < 90° (in front) the ray through the origin sees exactly 3,000 cd/m². */
#define LV_SCAN_CENTRE_CD_M2 3000.0
/* Half the centre tile's edge (m): points of the frame's z = 0 plane closer than this to the origin
 * (in x and y) show the centre tile. */
#define LV_SCAN_CENTRE_HALF_M 0.015

typedef struct lv_scan_files {
    char pack[4096];  /* the .lvpack */
    char proxy[4096]; /* its proxy mesh, glTF binary */
} lv_scan_files;

/* The bundled scan's files under `<repo_root>/target/nearfield-demo/` (named after the luminaire,
 * layout and size). A missing file is generated with the lumiview CLI — `$LUMIVIEW_CLI` if set, else
 * `<repo_root>/target/debug/lumiview` (`cargo build --bin lumiview`):
 *   lumiview pack --synth two-planes --layout rigo:1000 --size 256x256 --no-proxy --quiet -o PACK
 *   lumiview synth two-planes --proxy GLB
 * each written under a temporary name and renamed, so an interrupted run never leaves a partial
 * file. The CLI runs without this process's LD_PRELOAD (the sanitizer runtime). Prints what it
 * generates; prints why and returns false on failure. */
bool lv_scan_ensure(const char *repo_root, lv_scan_files *out);

/* "nearest", "idw4", "continuous" for LUMI_SELECTION_*, or "unknown". */
const char *lv_selection_name(uint32_t mode);
/* The inverse of lv_selection_name. */
bool lv_parse_selection(const char *s, uint32_t *mode);

#endif /* LV_SCAN_H */

// reflect101: the index a border pixel copies under OpenCV's BORDER_REFLECT_101
// (gfedcb|abcdefgh|gfedcba), for the hand-written separable passes that pad their own
// rows (HighPassWindow, PyramidLk) and must match OpenCV's filters at the edges.
#pragma once

namespace endotower::vision::detail {

// i may lie any distance outside [0, n); n >= 1.
inline int reflect101(int i, int n) {
    if (n == 1) return 0;
    while (i < 0 || i >= n) i = i < 0 ? -i : 2 * n - 2 - i;
    return i;
}

}  // namespace endotower::vision::detail

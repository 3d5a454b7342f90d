//! The ray caster's acceleration grids: the chessboard distance field and, per quadrant of
//! travel, the largest empty squares.

use super::{EMPTY, LIST, SOLID, World};

impl World {
    /// Chessboard distance (in cells) from each cell to the nearest non-empty cell.
    pub(super) fn build_distance(&mut self) {
        self.dist = self.chessboard_distance();
        for q in 0..4 {
            self.planes[q] = self.empty_squares(q);
        }
    }

    /// Two-pass chessboard distance transform of the cells (0 at non-empty cells, capped at
    /// `u16::MAX`).
    fn chessboard_distance(&self) -> Vec<u16> {
        let (nx, ny) = (self.nx, self.ny);
        let inf = u16::MAX as u32;
        let mut d: Vec<u32> = self
            .cells
            .iter()
            .map(|&c| if c == EMPTY { inf } else { 0 })
            .collect();
        for y in 0..ny {
            for x in 0..nx {
                let i = y * nx + x;
                let mut v = d[i];
                if x > 0 {
                    v = v.min(d[i - 1] + 1);
                }
                if y > 0 {
                    v = v.min(d[i - nx] + 1);
                    if x > 0 {
                        v = v.min(d[i - nx - 1] + 1);
                    }
                    if x + 1 < nx {
                        v = v.min(d[i - nx + 1] + 1);
                    }
                }
                d[i] = v.min(inf);
            }
        }
        for y in (0..ny).rev() {
            for x in (0..nx).rev() {
                let i = y * nx + x;
                let mut v = d[i];
                if x + 1 < nx {
                    v = v.min(d[i + 1] + 1);
                }
                if y + 1 < ny {
                    v = v.min(d[i + nx] + 1);
                    if x + 1 < nx {
                        v = v.min(d[i + nx + 1] + 1);
                    }
                    if x > 0 {
                        v = v.min(d[i + nx - 1] + 1);
                    }
                }
                d[i] = v.min(inf);
            }
        }
        d.into_iter().map(|v| v as u16).collect()
    }

    /// The plane of quadrant of travel `q` (bit 0: +x, bit 1: +y), in its mirrored cell
    /// coordinates: per cell the side of the largest empty square toward the quadrant.
    fn empty_squares(&self, q: usize) -> Vec<u8> {
        let (nx, ny) = (self.nx, self.ny);
        let (px, py) = (q & 1 == 1, q & 2 == 2);
        // Mirrored coordinates (mx, my): the quadrant's rays move toward +mx and +my.
        let mut plane = vec![0u8; nx * ny];
        let side = |plane: &[u8], mx: usize, my: usize| -> u32 {
            if mx >= nx || my >= ny {
                return 255; // Squares may reach the grid's edge.
            }
            match plane[my * nx + mx] {
                LIST => 0,
                v => u32::from(v),
            }
        };
        for my in (0..ny).rev() {
            let y = if py { my } else { ny - 1 - my };
            for mx in (0..nx).rev() {
                let x = if px { mx } else { nx - 1 - mx };
                plane[my * nx + mx] = match self.cells[y * nx + x] {
                    EMPTY => {
                        let m = side(&plane, mx + 1, my)
                            .min(side(&plane, mx, my + 1))
                            .min(side(&plane, mx + 1, my + 1));
                        (m + 1).min(u32::from(LIST) - 1) as u8
                    }
                    SOLID => 0,
                    _ => LIST,
                };
            }
        }
        plane
    }
}

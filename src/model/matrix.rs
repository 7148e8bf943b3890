//! A small dense row-major matrix: just what state-space realisation, the zero-order hold and the
//! predictive controllers need (products, sums, the matrix exponential). Orders stay below ~10,
//! so a dependency on a linear-algebra crate would buy nothing.
//!
//! The arithmetic methods panic on mismatched dimensions: they are called only on matrices whose
//! sizes the model constructors have already checked.

use super::error::ModelError;

/// A dense `rows × cols` matrix stored row by row.
#[derive(Debug, Clone, PartialEq)]
pub struct Mat {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl Mat {
    /// The zero matrix.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Self { rows, cols, data: vec![0.0; rows * cols] }
    }

    /// The identity of order `n`.
    pub fn identity(n: usize) -> Self {
        let mut m = Self::zeros(n, n);
        for i in 0..n {
            m[(i, i)] = 1.0;
        }
        m
    }

    /// A matrix from its rows; every row must have the same length.
    pub fn from_rows(rows: &[Vec<f64>]) -> Result<Self, ModelError> {
        let r = rows.len();
        let c = rows.first().map_or(0, Vec::len);
        if let Some(bad) = rows.iter().find(|row| row.len() != c) {
            return Err(ModelError::Dimension {
                what: "matrix row length".into(),
                expected: c,
                found: bad.len(),
            });
        }
        Ok(Self { rows: r, cols: c, data: rows.iter().flatten().copied().collect() })
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// The matrix product `self · other`.
    pub fn mul(&self, other: &Mat) -> Mat {
        assert_eq!(self.cols, other.rows, "matrix product dimensions");
        let mut out = Mat::zeros(self.rows, other.cols);
        for i in 0..self.rows {
            for k in 0..self.cols {
                let a = self[(i, k)];
                if a == 0.0 {
                    continue;
                }
                for j in 0..other.cols {
                    out[(i, j)] += a * other[(k, j)];
                }
            }
        }
        out
    }

    /// The product with a vector.
    pub fn mul_vec(&self, v: &[f64]) -> Vec<f64> {
        assert_eq!(self.cols, v.len(), "matrix-vector dimensions");
        (0..self.rows).map(|i| (0..self.cols).map(|j| self[(i, j)] * v[j]).sum()).collect()
    }

    /// `self + other`.
    pub fn add(&self, other: &Mat) -> Mat {
        assert_eq!((self.rows, self.cols), (other.rows, other.cols));
        let data = self.data.iter().zip(&other.data).map(|(a, b)| a + b).collect();
        Mat { rows: self.rows, cols: self.cols, data }
    }

    /// `s · self`.
    pub fn scale(&self, s: f64) -> Mat {
        Mat { rows: self.rows, cols: self.cols, data: self.data.iter().map(|a| a * s).collect() }
    }

    /// The largest absolute row sum (the induced ∞-norm).
    pub fn norm_inf(&self) -> f64 {
        (0..self.rows).map(|i| (0..self.cols).map(|j| self[(i, j)].abs()).sum::<f64>()).fold(0.0, f64::max)
    }

    /// The matrix exponential by scaling and squaring of a Taylor series. The scaled matrix has
    /// norm ≤ 0.5, where 20 Taylor terms are exact to machine precision.
    pub fn expm(&self) -> Mat {
        assert_eq!(self.rows, self.cols, "expm needs a square matrix");
        let norm = self.norm_inf();
        let squarings = if norm > 0.5 { (norm / 0.5).log2().ceil() as u32 } else { 0 };
        let a = self.scale(1.0 / f64::from(2u32.pow(squarings)));
        let mut term = Mat::identity(self.rows);
        let mut sum = Mat::identity(self.rows);
        for k in 1..=20 {
            term = term.mul(&a).scale(1.0 / f64::from(k));
            sum = sum.add(&term);
        }
        for _ in 0..squarings {
            sum = sum.mul(&sum);
        }
        sum
    }
}

impl std::ops::Index<(usize, usize)> for Mat {
    type Output = f64;
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        &self.data[i * self.cols + j]
    }
}

impl std::ops::IndexMut<(usize, usize)> for Mat {
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        &mut self.data[i * self.cols + j]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expm_of_rotation_generator_is_a_rotation() {
        let t = 2.7;
        let a = Mat::from_rows(&[vec![0.0, -t], vec![t, 0.0]]).unwrap();
        let e = a.expm();
        assert!((e[(0, 0)] - t.cos()).abs() < 1e-12);
        assert!((e[(1, 0)] - t.sin()).abs() < 1e-12);
        assert!((e[(0, 1)] + t.sin()).abs() < 1e-12);
    }

    #[test]
    fn expm_of_diagonal_is_elementwise() {
        let a = Mat::from_rows(&[vec![-3.0, 0.0], vec![0.0, 1.5]]).unwrap();
        assert!(Mat::from_rows(&[vec![1.0], vec![1.0, 2.0]]).is_err());
        let e = a.expm();
        assert!((e[(0, 0)] - (-3.0f64).exp()).abs() < 1e-12);
        assert!((e[(1, 1)] - 1.5f64.exp()).abs() < 1e-12);
        assert_eq!(e[(0, 1)], 0.0);
    }
}

//! Sensor noise, the EMVA 1288 linear photon-transfer model (docs/spec.md section 9).
//!
//! A pixel of linear radiance `L` (0..1) collects `mu_e = phi * t_e * L`
//! electrons on average in an exposure of `t_e` seconds (`phi`: the electrons
//! per second a white pixel collects, i.e. the light level). The electrons are
//! Poisson(`mu_e`) (shot noise) plus normal read noise of `sigma_d` electrons,
//! clipped at 0 and the full well; the digital number is `round(K e)`, clipped to
//! `0..2^bits - 1`. Images stay linear floats: a noisy pixel is `DN / (2^bits - 1)`,
//! so a shorter exposure is darker as well as noisier.
//!
//! Hence, before clipping, `E[DN] = K mu_e` and
//! `Var[DN] = K^2 (mu_e + sigma_d^2) + 1/12` (quantisation).

use crate::error::{Error, Result};
use crate::limits::MAX_EXACT_POISSON_MEAN_E;
// The noise's own `rand` (0.10), `rand_distr` (0.6) and RNG (Xoshiro256++): see core/Cargo.toml.
use rand10::SeedableRng;
use rand_distr06::{Distribution, Normal, Poisson};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

/// The noise parameters of a sensor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Noise {
    /// Electrons per second collected by a white pixel (`L = 1`): the light level, e-/s.
    pub phi_e_per_s: f64,
    /// Read (dark) noise, electrons RMS. Default 2.5.
    #[serde(default = "default_read")]
    pub read_noise_e: f64,
    /// Full-well capacity, electrons. Default 10,000.
    #[serde(default = "default_full_well")]
    pub full_well_e: f64,
    /// System gain `K`, digital numbers per electron. Default: the full well fills the range.
    #[serde(default)]
    pub gain_dn_per_e: Option<f64>,
    /// Bits of the digital number, 1..=16. Default 8.
    #[serde(default = "default_bits")]
    pub bits: u32,
    /// Seed of the noise (runs with the same seed are bit-identical). Default 0.
    #[serde(default)]
    pub seed: u64,
}

fn default_read() -> f64 {
    2.5
}
fn default_full_well() -> f64 {
    10_000.0
}
fn default_bits() -> u32 {
    8
}

impl Noise {
    /// A sensor at light level `phi_e_per_s` with the defaults above.
    pub fn at_light(phi_e_per_s: f64) -> Self {
        Noise {
            phi_e_per_s,
            read_noise_e: default_read(),
            full_well_e: default_full_well(),
            gain_dn_per_e: None,
            bits: default_bits(),
            seed: 0,
        }
    }

    /// Largest digital number, `2^bits - 1`.
    pub fn max_dn(&self) -> f64 {
        ((1u64 << self.bits) - 1) as f64
    }

    /// The gain `K`, DN per electron (given, or `max_dn / full_well`).
    pub fn gain(&self) -> f64 {
        self.gain_dn_per_e
            .unwrap_or(self.max_dn() / self.full_well_e)
    }

    /// Rejects parameters out of range, naming the key.
    pub fn validate(&self) -> Result<()> {
        let bad = |k: &str, m: String| Err(Error::invalid(format!("noise.{k}"), m));
        crate::limits::check_light("noise.phi_e_per_s", self.phi_e_per_s)?;
        if !(self.read_noise_e.is_finite() && self.read_noise_e >= 0.0) {
            return bad(
                "read_noise_e",
                format!("must be >= 0 e-, got {}", self.read_noise_e),
            );
        }
        if !(self.full_well_e.is_finite() && self.full_well_e >= 1.0) {
            return bad(
                "full_well_e",
                format!("must be >= 1 e-, got {}", self.full_well_e),
            );
        }
        if let Some(k) = self.gain_dn_per_e {
            if !(k.is_finite() && k > 0.0) {
                return bad("gain_dn_per_e", format!("must be > 0 DN/e-, got {k}"));
            }
        }
        if !(1..=16).contains(&self.bits) {
            return bad("bits", format!("must be 1..=16, got {}", self.bits));
        }
        Ok(())
    }

    /// Applies the model to linear radiances `pixels` (0..1, any layout)
    /// exposed for `exposure_s`, in place, with the RNG stream `stream`
    /// (0 for a frame; another value for a second image of the same frame,
    /// e.g. its sharp twin). Deterministic for a given seed and stream: the
    /// values are cut into chunks of [`Noise::CHUNK`], each drawn from its own
    /// RNG (Xoshiro256++, seeded by seed, stream and chunk number), in parallel.
    pub fn apply(&self, pixels: &mut [f32], exposure_s: f64, stream: u64) -> Result<()> {
        use rayon::prelude::*;
        let draw = Draw::new(self, exposure_s, stream)?;
        let max_dn = self.max_dn();
        pixels
            .par_chunks_mut(Self::CHUNK)
            .enumerate()
            .try_for_each(|(c, chunk)| {
                let mut rng = draw.rng(c);
                for p in chunk.iter_mut() {
                    *p = (draw.dn(*p, &mut rng)? / max_dn) as f32;
                }
                Ok(())
            })
    }

    /// The digital numbers of [`Noise::apply`]: the same draws (same seed,
    /// stream and chunks), returned as codes `0..=2^bits - 1` instead of
    /// `DN / (2^bits - 1)`, so `apply` gives `dn as f64 / max_dn` as f32 of these.
    pub fn apply_dn(&self, pixels: &[f32], exposure_s: f64, stream: u64) -> Result<Vec<u16>> {
        use rayon::prelude::*;
        let draw = Draw::new(self, exposure_s, stream)?;
        let mut out = vec![0u16; pixels.len()];
        pixels
            .par_chunks(Self::CHUNK)
            .zip(out.par_chunks_mut(Self::CHUNK))
            .enumerate()
            .try_for_each(|(c, (chunk, codes))| {
                let mut rng = draw.rng(c);
                for (p, d) in chunk.iter().zip(codes.iter_mut()) {
                    // An integer in 0..=65535 (bits <= 16): exact as u16.
                    *d = draw.dn(*p, &mut rng)? as u16;
                }
                Ok(())
            })?;
        Ok(out)
    }

    /// Values per RNG chunk of [`Noise::apply`].
    pub const CHUNK: usize = 16384;
}

/// One call of [`Noise::apply`] / [`Noise::apply_dn`]: the sensor's
/// constants and the RNG seeding, shared by both so their draws are the same.
struct Draw {
    read: Normal<f64>,
    /// Gain, DN/e-.
    k: f64,
    max_dn: f64,
    full_well_e: f64,
    /// Electrons of a white pixel in this exposure.
    scale: f64,
    /// The stream's seed (chunk seeds are derived from it).
    base: u64,
}

impl Draw {
    fn new(noise: &Noise, exposure_s: f64, stream: u64) -> Result<Self> {
        noise.validate()?;
        Ok(Draw {
            read: Normal::new(0.0, noise.read_noise_e)
                .map_err(|e| Error::invalid("noise.read_noise_e", e.to_string()))?,
            k: noise.gain(),
            max_dn: noise.max_dn(),
            full_well_e: noise.full_well_e,
            scale: noise.phi_e_per_s * exposure_s,
            base: noise.seed ^ stream.wrapping_mul(0x9E37_79B9_7F4A_7C15),
        })
    }

    /// The RNG of chunk `c` (of [`Noise::CHUNK`] values).
    fn rng(&self, c: usize) -> Xoshiro256PlusPlus {
        Xoshiro256PlusPlus::seed_from_u64(
            self.base ^ (c as u64 + 1).wrapping_mul(0xD1B5_4A32_D192_ED03),
        )
    }

    /// The digital number (an integer in `0..=max_dn`, as f64) of a pixel of linear radiance `p`.
    #[inline]
    fn dn(&self, p: f32, rng: &mut Xoshiro256PlusPlus) -> Result<f64> {
        let mu = self.scale * (p as f64).clamp(0.0, f64::MAX);
        let shot = shot_noise(mu, rng)?;
        let e = (shot + self.read.sample(rng)).clamp(0.0, self.full_well_e);
        Ok((self.k * e).round().clamp(0.0, self.max_dn))
    }
}

/// The electrons of a pixel whose mean is `mu` e- (shot noise), bounded in
/// time for every mean: the exact Poisson sampler up to
/// [`MAX_EXACT_POISSON_MEAN_E`] (its seeded draws unchanged), above it the
/// normal approximation `N(mu, mu)` rounded and clamped at 0; 0 for a mean
/// of 0 (or NaN), and `f64::MAX` (clipped at the full well by the caller)
/// for an infinite one.
pub fn shot_noise<R: rand10::Rng + ?Sized>(mu: f64, rng: &mut R) -> Result<f64> {
    if mu.is_nan() || mu <= 0.0 {
        Ok(0.0)
    } else if mu == f64::INFINITY {
        Ok(f64::MAX)
    } else if mu <= MAX_EXACT_POISSON_MEAN_E {
        Ok(Poisson::new(mu)
            .map_err(|e| Error::invalid("noise", format!("mean {mu} e-: {e}")))?
            .sample(rng))
    } else {
        let z: f64 = rand_distr06::StandardNormal.sample(rng);
        Ok((mu + mu.sqrt() * z).round().max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Photon transfer (EMVA 1288): over a flat field the DN mean is `K mu_e`
    /// and the variance `K^2 (mu_e + sigma_d^2) + 1/12`, within sampling error.
    #[test]
    fn photon_transfer() {
        for &(phi, l, t, bits) in &[
            (50_000.0, 0.5, 0.07, 12u32),
            (20_000.0, 0.3, 0.01, 10),
            (1e5, 0.8, 0.03, 12),
        ] {
            let noise = Noise {
                bits,
                seed: 7,
                ..Noise::at_light(phi)
            };
            let n = 200_000;
            let mut px = vec![l as f32; n];
            noise.apply(&mut px, t, 0).unwrap();
            let dn: Vec<f64> = px.iter().map(|&p| p as f64 * noise.max_dn()).collect();
            let mean = dn.iter().sum::<f64>() / n as f64;
            let var = dn.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            let k = noise.gain();
            let mu_e = phi * t * l as f32 as f64;
            assert!(mu_e < 0.8 * noise.full_well_e, "stay below the full well");
            let (em, ev) = (k * mu_e, k * k * (mu_e + 2.5f64.powi(2)) + 1.0 / 12.0);
            // Standard errors: sqrt(var / n) for the mean, var sqrt(2 / n) for the variance.
            let (sm, sv) = ((ev / n as f64).sqrt(), ev * (2.0 / n as f64).sqrt());
            assert!(
                (mean - em).abs() < 5.0 * sm,
                "mean {mean} vs {em} (se {sm})"
            );
            assert!(
                (var - ev).abs() < 5.0 * sv,
                "variance {var} vs {ev} (se {sv})"
            );
        }
    }

    #[test]
    fn seeded_and_clipped() {
        let noise = Noise::at_light(2e6);
        let mut a = vec![0.2f32; 1000];
        let mut b = a.clone();
        noise.apply(&mut a, 0.05, 0).unwrap();
        noise.apply(&mut b, 0.05, 0).unwrap();
        assert_eq!(a, b);
        let (mut c, mut d) = (vec![0.02f32; 1000], vec![0.02f32; 1000]);
        noise.apply(&mut c, 0.05, 0).unwrap();
        noise.apply(&mut d, 0.05, 1).unwrap();
        assert_ne!(c, d, "another stream is another realisation");
        // 2e6 e-/s x 0.05 s x 0.2 = 20,000 e-: twice the full well, so white.
        assert!(a.iter().all(|&p| p == 1.0));
        let mut dark = vec![0.0f32; 1000];
        noise.apply(&mut dark, 0.05, 0).unwrap();
        assert!(dark.iter().all(|&p| (0.0..0.01).contains(&p)));
    }

    /// Up to the threshold the draws are the exact sampler's, seed for seed
    /// (goldens keep their bytes); above it they are bounded in time for
    /// every mean, with the mean and variance of Poisson(mu).
    #[test]
    fn shot_noise_is_exact_below_and_bounded_above() {
        for mu in [0.5, 11.9, 12.0, 1400.0, 2e4, 1e6, MAX_EXACT_POISSON_MEAN_E] {
            let (mut a, mut b) = (
                Xoshiro256PlusPlus::seed_from_u64(3),
                Xoshiro256PlusPlus::seed_from_u64(3),
            );
            let p = Poisson::new(mu).unwrap();
            for _ in 0..200 {
                assert_eq!(shot_noise(mu, &mut a).unwrap(), p.sample(&mut b), "{mu}");
            }
        }
        let start = std::time::Instant::now();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        for mu in [1.0000001e9, 1e12, 1e15, 1e200, 1e305, 1.7e308, f64::MAX] {
            let n = 20_000;
            // Each draw in standard units: (draw - mu) / sqrt(mu).
            let z: Vec<f64> = (0..n)
                .map(|_| {
                    let d = shot_noise(mu, &mut rng).unwrap();
                    assert!(d.is_finite() && d >= 0.0, "{mu}: {d}");
                    (d - mu) / mu.sqrt()
                })
                .collect();
            assert!(z.iter().all(|z| z.abs() < 7.0), "{mu}");
            if mu > 1e16 {
                continue; // sqrt(mu) nears the spacing of f64 values at mu
            }
            let mean = z.iter().sum::<f64>() / n as f64;
            let var = z.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            // Standard errors of the mean and the variance of N(0, 1).
            let (sm, sv) = ((1.0 / n as f64).sqrt(), (2.0 / n as f64).sqrt());
            assert!(mean.abs() < 5.0 * sm, "{mu}: mean {mean}");
            assert!((var - 1.0).abs() < 5.0 * sv, "{mu}: variance {var}");
        }
        assert_eq!(shot_noise(f64::INFINITY, &mut rng).unwrap(), f64::MAX);
        assert_eq!(shot_noise(0.0, &mut rng).unwrap(), 0.0);
        assert_eq!(shot_noise(f64::NAN, &mut rng).unwrap(), 0.0);
        assert!(start.elapsed().as_secs_f64() < 5.0, "{:?}", start.elapsed());
    }

    /// An absurd mean through the whole model: saturated white, quickly.
    #[test]
    fn absurd_means_saturate() {
        let noise = Noise::at_light(crate::limits::MAX_LIGHT_E_PER_S);
        for t in [1.0, 1e300, f64::MAX] {
            let mut px = vec![0.7f32; 3 * Noise::CHUNK];
            noise.apply(&mut px, t, 0).unwrap();
            assert!(px.iter().all(|&p| p == 1.0), "{t}");
        }
        let e = Noise::at_light(1e308).validate().unwrap_err().to_string();
        assert!(e.contains("noise.phi_e_per_s") && e.contains("1e12"), "{e}");
    }

    #[test]
    fn bad_parameters_name_the_key() {
        let e = Noise {
            bits: 0,
            ..Noise::at_light(1.0)
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("noise.bits"), "{e}");
        let e = Noise::at_light(-1.0).validate().unwrap_err();
        assert!(e.to_string().contains("noise.phi_e_per_s"), "{e}");
        let e = Noise {
            read_noise_e: f64::NAN,
            ..Noise::at_light(1.0)
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("noise.read_noise_e"), "{e}");
    }

    /// `apply_dn` draws what `apply` draws: `apply` gives `dn / max_dn`, value
    /// for value, over several chunks, bit depths and lights (dark, where the
    /// means fall below 12 e- and Knuth's sampler runs, and bright, where
    /// Ahrens-Dieter's does and the full well clips), and values clipped at 0.
    #[test]
    fn apply_dn_is_apply_in_codes() {
        let n = 2 * Noise::CHUNK + 123;
        let px: Vec<f32> = (0..n)
            .map(|i| ((i * 7919) % 1000) as f32 / 900.0 - 0.05)
            .collect();
        for (phi, bits, t) in [(300.0, 8u32, 0.01), (50_000.0, 12, 0.07), (1e6, 16, 0.2)] {
            let noise = Noise {
                bits,
                seed: 3,
                ..Noise::at_light(phi)
            };
            let mut a = px.clone();
            noise.apply(&mut a, t, 5).unwrap();
            let dn = noise.apply_dn(&px, t, 5).unwrap();
            let max = noise.max_dn();
            assert!(dn.iter().all(|&d| f64::from(d) <= max));
            assert!(dn.contains(&0), "{phi}: some code clipped at 0");
            for (x, d) in a.iter().zip(&dn) {
                assert_eq!(x.to_bits(), ((f64::from(*d) / max) as f32).to_bits());
            }
        }
    }
}

//! The dataset's textures: the built-in set (`textures = "builtin:"`, the
//! default), compiled into the library from `assets/textures/` so the
//! defaults work from any directory and from the installed Python wheel, or
//! a folder of PNG/JPEG files.
//!
//! The built-in files are byte for byte those of `assets/textures/`, under
//! the same names: a dataset made with them is the one made with that folder
//! (same items, same fingerprint, which covers textures by content).

use crate::error::{Error, Result};
use crate::render::texture::MipTexture;
use sha2::{Digest, Sha256};
use std::path::Path;

/// The `textures` value naming the built-in set.
pub const BUILTIN: &str = "builtin:";

/// The built-in textures, by file name (sorted): copies of scikit-image's
/// CC0 / public-domain images, see [`LICENSE`].
pub const BUILTIN_FILES: [(&str, &[u8]); 5] = [
    (
        "brick.png",
        include_bytes!("../../../assets/textures/brick.png"),
    ),
    (
        "chelsea.png",
        include_bytes!("../../../assets/textures/chelsea.png"),
    ),
    (
        "coffee.png",
        include_bytes!("../../../assets/textures/coffee.png"),
    ),
    (
        "gravel.png",
        include_bytes!("../../../assets/textures/gravel.png"),
    ),
    (
        "rocket.jpg",
        include_bytes!("../../../assets/textures/rocket.jpg"),
    ),
];

/// The built-in textures' origin and licences (`assets/textures/LICENSE.md`).
pub const LICENSE: &str = include_str!("../../../assets/textures/LICENSE.md");

/// True when `textures` names the built-in set.
pub fn is_builtin(textures: &Path) -> bool {
    textures.as_os_str() == BUILTIN
}

/// The bytes of the built-in texture `name`.
pub fn builtin(name: &str) -> Result<&'static [u8]> {
    BUILTIN_FILES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, b)| *b)
        .ok_or_else(|| {
            Error::invalid(
                "texture",
                format!(
                    "{} is not a built-in texture ({})",
                    crate::error::quote(name),
                    BUILTIN_FILES.map(|(n, _)| n).join(", ")
                ),
            )
        })
}

/// Decodes a built-in texture as the file of the same name would be
/// ([`MipTexture::load`]: sRGB to linear light, mip-mapped).
pub fn load_builtin(name: &str) -> Result<MipTexture> {
    let bytes = builtin(name)?;
    let img = image::load_from_memory(bytes)
        .map_err(|e| Error::invalid(format!("built-in texture {name}"), e.to_string()))?;
    MipTexture::from_srgb8(&img.to_rgb8())
}

/// Size and SHA-256 (hex) of a built-in texture, as a file's would be.
pub fn builtin_sum(name: &str) -> Result<(u64, String)> {
    let bytes = builtin(name)?;
    Ok((bytes.len() as u64, format!("{:x}", Sha256::digest(bytes))))
}

/// Size and SHA-256 (hex) of the texture file `p`, read in bounded memory.
pub fn file_sum(p: &Path) -> Result<(u64, String)> {
    let mut f = crate::io::input::open_file(p)?;
    let mut h = Sha256::new();
    let n = std::io::copy(&mut f, &mut h).map_err(|e| Error::io(p, e))?;
    Ok((n, format!("{:x}", h.finalize())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_names_are_sorted_and_decode() {
        let names = BUILTIN_FILES.map(|(n, _)| n);
        let mut sorted = names;
        sorted.sort();
        assert_eq!(names, sorted);
        let t = load_builtin("chelsea.png").unwrap();
        assert_eq!((t.levels[0].w, t.levels[0].h), (451, 300));
        assert!(builtin("nope.png").is_err());
        assert!(LICENSE.contains("CC0"));
    }
}

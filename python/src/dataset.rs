//! Dataset items from Python (`mmbm.BlurDataset`): a configuration opened
//! once (`DatasetMaker`), then item `i` made into a directory with the same
//! code, and so the same bytes, as `mmbm dataset`.

use crate::err;
use crate::interrupt::interruptible;
use mmbm_lab::dataset::{make_item, DatasetConfig, Record, Sources};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A dataset configuration with its sources (textures, logs) opened.
#[pyclass(module = "mmbm._mmbm", frozen)]
pub struct DatasetMaker {
    cfg: DatasetConfig,
    src: Sources,
    rec: Record,
}

#[pymethods]
impl DatasetMaker {
    /// From a TOML file (`path`) or TOML text (`toml`); neither: the defaults.
    #[new]
    #[pyo3(signature = (path=None, toml=None))]
    fn new(py: Python<'_>, path: Option<PathBuf>, toml: Option<String>) -> PyResult<Self> {
        interruptible(py, err, || {
            let cfg = match (path, toml) {
                (Some(p), None) => DatasetConfig::load(&p)?,
                (None, Some(t)) => DatasetConfig::from_toml(&t, "toml")?,
                (None, None) => DatasetConfig::default(),
                (Some(_), Some(_)) => {
                    return Err(mmbm::Error::invalid(
                        "BlurDataset",
                        "give the configuration as a path or as TOML text, not both",
                    ))
                }
            };
            cfg.validate()?;
            let src = Sources::open(&cfg)?;
            let rec = Record::of(&cfg, &src)?;
            Ok(DatasetMaker { cfg, src, rec })
        })
    }

    /// Items in the dataset.
    #[getter]
    fn count(&self) -> u64 {
        self.cfg.count
    }

    /// The configuration's fingerprint (as in `DIR/dataset.json`).
    #[getter]
    fn fingerprint(&self) -> String {
        self.rec.fingerprint.clone()
    }

    /// Makes item `index` into the existing directory `dir`; returns its
    /// manifest line (JSON).
    fn make(&self, py: Python<'_>, index: u64, dir: PathBuf) -> PyResult<String> {
        if index >= self.cfg.count {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!(
                "item {index}: the dataset has {} items",
                self.cfg.count
            )));
        }
        let line = interruptible(py, err, || {
            make_item(&self.cfg, &self.src, &self.rec, index, &dir)
        })?;
        serde_json::to_string(&line)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))
    }
}

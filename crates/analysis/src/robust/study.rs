//! A tolerance analysis as a study of samples: what journals, shards,
//! resumes and merges it (`crate::study`), in the program and the Python
//! package alike.

use fistage_model::{Loaded, RobotSpec};

use super::{RobustSpec, SampleResult, table};
use crate::study::{Provenance, Study, StudyError};

/// A tolerance analysis as a [`Study`] of samples (journal, shards,
/// resume, merge).
pub struct RobustStudy<'a> {
    /// The scenario, loaded.
    pub loaded: &'a Loaded,
    /// Its robot file as read (what the draws write into).
    pub robot_file: &'a RobotSpec,
    /// The design and its assessment.
    pub spec: &'a RobustSpec,
}

impl RobustStudy<'_> {
    /// What decides the samples' numbers, as shard `shard` (the program's
    /// and the Python package's analyses of one scenario agree on it).
    /// `scenario_text`, when given, stands for the scenario file's content
    /// (a scenario made in Python).
    pub fn provenance(
        &self,
        scenario_text: Option<&[u8]>,
        shard: Option<(usize, usize)>,
    ) -> Result<Provenance, StudyError> {
        let spec = self.spec;
        let provenance = Provenance::of_study(
            "robust",
            (&self.loaded.scenario.file, scenario_text),
            &self.loaded.scenario.robot,
            &format!(
                "{} samples, seed {}, {:?}, {:?}",
                spec.samples, spec.seed, spec.sampling, spec.dimensions
            ),
            &format!("{:?}", spec.assessment),
            shard,
        )?;
        // The fit drawn from is part of what decides the numbers.
        match &spec.fitted {
            Some(fitted) => Ok(provenance
                .with_file("fit drawn from", &fitted.file)?
                .with_item("fit draw", format!("{:?}", fitted.draw))),
            None => Ok(provenance),
        }
    }
}

impl Study for RobustStudy<'_> {
    type Row = SampleResult;
    const TABLE: &'static str = "samples.csv";
    const ITEMS: &'static str = "samples";
    fn len(&self) -> usize {
        self.spec.samples
    }
    fn header(&self) -> String {
        table::header(self.spec)
    }
    fn row(&self, row: &SampleResult) -> String {
        table::row(row)
    }
    fn index(row: &SampleResult) -> usize {
        row.index
    }
    fn parse_row(&self, line: &str) -> Option<SampleResult> {
        table::parse_row(line, self.spec)
    }
    fn compute(
        &self,
        indices: &[usize],
        threads: usize,
        done: &(dyn Fn(&SampleResult, usize) + Sync),
    ) -> Vec<SampleResult> {
        self.spec
            .run(self.loaded, self.robot_file, indices, threads, done)
    }
}

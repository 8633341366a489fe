//! A flow's `depart_lane`: SUMO 1.8's `departLane` values mapc simulates, read from a scenario's text and
//! written back as SUMO's attribute (one vocabulary for the scenario check, the simulator and the SUMO export).

/// SUMO's `departLane` of a flow.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DepartLane {
    /// The rightmost lane (SUMO 1.8's default `first`).
    #[default]
    First,
    /// Of the lanes that go furthest on the route without a lane change, the one with the least brutto
    /// occupancy when the vehicle is inserted (SUMO 1.8's `best`: `free` among the best lanes).
    Best,
    /// This lane (0 = rightmost).
    Index(u8),
    /// A lane of the entry road drawn uniformly from the run's random numbers at every insertion attempt (SUMO's
    /// `random`).
    Random,
    /// The entry road's lane with the least brutto occupancy when the vehicle is inserted, the rightmost on a
    /// tie (SUMO 1.8's `free` with the default depart position).
    Free,
}

impl DepartLane {
    /// From a scenario's text: `first`, `best`, `random`, `free` or a lane index.
    pub fn parse(text: &str) -> Result<DepartLane, String> {
        match text {
            "first" => Ok(DepartLane::First),
            "best" => Ok(DepartLane::Best),
            "random" => Ok(DepartLane::Random),
            "free" => Ok(DepartLane::Free),
            _ => text.parse::<u8>().map(DepartLane::Index).map_err(|_| {
                format!(
                    "depart_lane `{text}` is not `first`, `best`, `random`, `free` or a lane index (0 = rightmost)"
                )
            }),
        }
    }

    /// SUMO's `departLane` attribute value, which [`DepartLane::parse`] reads back.
    pub fn sumo_value(self) -> String {
        match self {
            DepartLane::First => "first".into(),
            DepartLane::Best => "best".into(),
            DepartLane::Index(i) => i.to_string(),
            DepartLane::Random => "random".into(),
            DepartLane::Free => "free".into(),
        }
    }

    /// The entry road's lane index; for `random`, `free` and `best`, whose lane is chosen at each insertion
    /// attempt, the rightmost (the lane the vehicle is created on while it waits).
    pub fn start_lane(self) -> Option<u8> {
        match self {
            DepartLane::First | DepartLane::Random | DepartLane::Free | DepartLane::Best => Some(0),
            DepartLane::Index(i) => Some(i),
        }
    }

    /// Whether the lane is chosen when the vehicle is inserted (`random`, `free`, `best`) rather than once for
    /// the flow.
    pub fn chosen_at_insertion(self) -> bool {
        matches!(
            self,
            DepartLane::Random | DepartLane::Free | DepartLane::Best
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_value_reads_back_from_its_sumo_text() {
        for d in [
            DepartLane::First,
            DepartLane::Best,
            DepartLane::Index(0),
            DepartLane::Index(4),
            DepartLane::Random,
            DepartLane::Free,
        ] {
            assert_eq!(DepartLane::parse(&d.sumo_value()), Ok(d));
        }
        assert!(DepartLane::parse("leftmost").is_err());
        assert!(DepartLane::parse("-1").is_err());
    }
}

//! `gpuwars tune`: the trade made for the user. A scene's game choices (those of
//! `tradeoff`'s game table) are measured on this machine and backend, speeds in interleaved
//! rounds and contacts against the exact audit; the most accurate choice that holds the
//! target speed with a margin is written as a new scene file, edited from the given one.

use std::path::PathBuf;

use anyhow::{Context as _, bail};
use serde::Serialize;
use toml_edit::{DocumentMut, Item, Table, value};

use super::Provenance;
use super::rounds::Rate;
use super::tradeoff::{FrameTiming, GameRow, Measure, RunSizes, estimate, game_choices, game_rows};
use crate::Device;
use crate::files::{figure, shown, write_atomically};
use crate::game::Scene;
use crate::sim::{Physics, Sweep};
use crate::terminal::progress;

/// How `gpuwars tune` runs.
#[derive(Clone, Debug)]
pub struct TuneOptions {
    /// The scene to tune.
    pub scene: Scene,
    /// The scene as the user named it.
    pub scene_given: String,
    /// What the tuned scene must hold.
    pub target: Target,
    /// How far above the target the slowest timed round must be (0.2: 20%).
    pub margin: f64,
    /// Small sizes and short runs.
    pub quick: bool,
    /// The choices to measure besides the scene as given, by their names in `tradeoff`'s
    /// game table; empty: every one.
    pub only: Vec<String>,
    /// Seed of every game.
    pub seed: u32,
    /// Where the tuned scene goes.
    pub out: PathBuf,
    /// Show a progress bar (on a terminal).
    pub progress: bool,
}

/// What `tune` found and chose.
#[derive(Clone, Debug, Serialize)]
pub struct TuneReport {
    /// Where and when.
    pub machine: Provenance,
    /// The scene as the user named it.
    pub scene: String,
    /// What the tuned scene must hold.
    pub target: Target,
    /// The margin asked for.
    pub margin: f64,
    /// Every choice measured, as `tradeoff`'s game table has it.
    pub rows: Vec<GameRow>,
    /// The row chosen.
    pub chosen: usize,
    /// Each other row, and why it was not chosen.
    pub rejected: Vec<(usize, String)>,
    /// Where the tuned scene was written.
    pub out: String,
}

/// What a tuned scene must hold on this machine.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Target {
    /// Steps per second of the game alone.
    StepsPerSecond(f64),
    /// Frames per second, each frame the steps due in its share of game time and the
    /// frame drawn as `play` draws it, at this size.
    FramesPerSecond {
        /// Frames a second.
        fps: f64,
        /// The frame's width and height in pixels.
        size: (u32, u32),
    },
}

impl Target {
    /// The rate asked for.
    fn value(self) -> f64 {
        match self {
            Target::StepsPerSecond(rate) => rate,
            Target::FramesPerSecond { fps, .. } => fps,
        }
    }

    /// Its unit.
    fn unit(self) -> &'static str {
        match self {
            Target::StepsPerSecond(_) => "steps/s",
            Target::FramesPerSecond { .. } => "frames/s",
        }
    }

    /// The frames [`game_rows`] must time for it.
    fn frames(self) -> Option<FrameTiming> {
        match self {
            Target::StepsPerSecond(_) => None,
            Target::FramesPerSecond { fps, size } => Some(FrameTiming { fps, size }),
        }
    }

    /// `row`'s rate in this target's unit.
    fn rate(self, row: &GameRow) -> Rate {
        match self {
            Target::StepsPerSecond(_) => steps_rate(row),
            Target::FramesPerSecond { .. } => row.frames_per_s.unwrap_or_default(),
        }
    }

    /// `rate` in words: `median unit (slowest–fastest)`.
    fn shown(self, rate: Rate) -> String {
        rate_words(rate, self.unit())
    }
}

/// `row`'s steps per second over the rounds.
fn steps_rate(row: &GameRow) -> Rate {
    Rate {
        median: row.steps_per_s,
        low: row.steps_per_s_range.0,
        high: row.steps_per_s_range.1,
    }
}

/// `rate` in `unit` in words: `median unit (slowest–fastest)`.
fn rate_words(rate: Rate, unit: &str) -> String {
    format!(
        "{} {unit} ({}–{})",
        figure(rate.median),
        figure(rate.low),
        figure(rate.high)
    )
}

/// The choices of `all` named in `only`, the scene as given (the first, `default`) always
/// kept as the one the others are weighed against; every one where `only` is empty. A name
/// that is not a choice of this scene is an error listing those that are.
fn selected(all: Vec<(String, Scene)>, only: &[String]) -> anyhow::Result<Vec<(String, Scene)>> {
    if let Some(unknown) = only.iter().find(|n| !all.iter().any(|(c, _)| c == *n)) {
        let names: Vec<String> = all.iter().map(|(c, _)| format!("`{c}`")).collect();
        bail!(
            "--choice: `{unknown}` is not a choice of this scene; its choices are {}",
            names.join(", ")
        );
    }
    Ok((all.into_iter().enumerate())
        .filter(|(i, (c, _))| *i == 0 || only.is_empty() || only.contains(c))
        .map(|(_, choice)| choice)
        .collect())
}

/// The slowest round a choice may have and still hold `target` with `margin`.
pub fn needed(target: f64, margin: f64) -> f64 {
    target * (1.0 + margin)
}

/// How good a measured row is, best first: contacts missed per thousand, then what else
/// the audit holds against it (contacts counted extra, with the wrong body or late, per
/// thousand), then the mean penetration at a step's end; then speed in `target`'s unit,
/// fastest first.
fn rank(row: &GameRow, target: Target) -> (f64, f64, f64, f64) {
    let a = row.accuracy.as_ref();
    let per = |v: Option<f64>| v.unwrap_or(0.0);
    let missed = a.map_or(f64::INFINITY, |a| per(a.missed));
    let wrong = a.map_or(f64::INFINITY, |a| {
        per(a.extra) + per(a.wrong_partner) + per(a.late)
    });
    let depth = a.map_or(f64::INFINITY, |a| a.depth_mean.unwrap_or(0.0));
    (missed, wrong, depth, -target.rate(row).median)
}

/// The most accurate of `rows` whose slowest round holds `target` with `margin` (fewest
/// contacts missed, then fewest extra, with the wrong body or late, then the shallowest
/// penetration, then the fastest), and why each other was not chosen; an error in words
/// naming the fastest choice and its speed where none holds it.
pub fn choose(
    rows: &[GameRow],
    target: Target,
    margin: f64,
) -> Result<(usize, Vec<(usize, String)>), String> {
    let need = needed(target.value(), margin);
    let unit = target.unit();
    let holds = |r: &GameRow| r.skipped.is_none() && target.rate(r).low >= need;
    let best = (0..rows.len())
        .filter(|&i| holds(&rows[i]))
        .min_by(|&i, &j| {
            rank(&rows[i], target)
                .partial_cmp(&rank(&rows[j], target))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .ok_or_else(|| {
            match (rows.iter())
                .filter(|r| r.skipped.is_none())
                .max_by(|a, b| target.rate(a).low.total_cmp(&target.rate(b).low))
            {
                Some(fastest) => format!(
                    "no choice holds {} {unit} with its slowest round ({} with the {}% margin): \
                     the fastest, `{}`, ran {}; lower the target, or tune a smaller scene",
                    figure(target.value()),
                    figure(need),
                    format!("{:.1}", margin * 100.0).trim_end_matches(".0"),
                    fastest.choice,
                    target.shown(target.rate(fastest)),
                ),
                None => {
                    let why: Vec<String> = (rows.iter())
                        .filter_map(|r| Some(format!("`{}`: {}", r.choice, r.skipped.as_ref()?)))
                        .collect();
                    format!("no choice could be measured: {}", why.join("; "))
                }
            }
        })?;
    let rejected = (0..rows.len())
        .filter(|&i| i != best)
        .map(|i| {
            let r = &rows[i];
            let why = match &r.skipped {
                Some(why) => format!("not measured: {why}"),
                None if !holds(r) => format!(
                    "too slow: its slowest round ran {} {unit}, {} needed",
                    figure(target.rate(r).low),
                    figure(need)
                ),
                None => worse_than(r, &rows[best], target),
            };
            (i, why)
        })
        .collect();
    Ok((best, rejected))
}

/// Why `row`, fast enough, ranks after `chosen` (see [`rank`]), in words.
fn worse_than(row: &GameRow, chosen: &GameRow, target: Target) -> String {
    let (r, c) = (rank(row, target), rank(chosen, target));
    if r.0 != c.0 {
        format!(
            "misses more contacts ({} per thousand, against {})",
            figure(r.0),
            figure(c.0)
        )
    } else if r.1 != c.1 {
        format!(
            "as many missed, more counted extra, with the wrong body or late ({} per thousand, \
             against {})",
            figure(r.1),
            figure(c.1)
        )
    } else if r.2 != c.2 {
        format!(
            "as exact in its contacts, deeper in them at a step's end (mean {}, against {})",
            figure(r.2),
            figure(c.2)
        )
    } else {
        format!(
            "as accurate, slower ({} {}, against {})",
            figure(-r.3),
            target.unit(),
            figure(-c.3)
        )
    }
}

/// The text of `given` (read from `source`) changed to `tuned`: the world's step, the
/// physics keys that differ, and each kind's `swept`; comments and layout kept. Only those
/// may differ between the two scenes.
pub fn tuned_toml(given: &Scene, tuned: &Scene, note: &str) -> anyhow::Result<String> {
    let mut doc: DocumentMut = given.source.parse().context("the scene's own text")?;
    let (g, t) = (&given.world, &tuned.world);
    if g.dt != t.dt {
        table(&mut doc, "world")["dt"] = value(f64::from(t.dt));
    }
    // The physics as the scene file's [physics] table writes it; the keys that differ.
    let keys = |p: &Physics| toml::Table::try_from(p).context("the physics as TOML");
    let (gp, tp) = (keys(&g.physics)?, keys(&t.physics)?);
    if gp != tp {
        let table = table(&mut doc, "physics");
        for (key, v) in &tp {
            if gp.get(key) != Some(v) {
                table[key] = value(v.to_string().parse::<toml_edit::Value>()?);
            }
        }
        for key in gp.keys().filter(|k| !tp.contains_key(*k)) {
            table.remove(key);
        }
    }
    for (k, (gk, tk)) in g.kinds.iter().zip(&t.kinds).enumerate() {
        if gk.sweep == tk.sweep {
            continue;
        }
        let kinds = doc["kinds"]
            .as_array_of_tables_mut()
            .context("the scene's [[kinds]]")?;
        let kind = kinds.get_mut(k).context("a kind of the scene")?;
        match tk.sweep {
            Sweep::On => kind["swept"] = value(true),
            Sweep::Off => kind["swept"] = value(false),
            Sweep::Auto => {
                kind.remove("swept");
            }
        }
    }
    let text = format!("{note}{doc}");
    // The file must read back as the scene chosen, whatever the edit did.
    let read = Scene::from_toml(&text, "the tuned scene")?;
    if read.world != tuned.world || read.game != tuned.game {
        bail!("the tuned scene does not read back as the choice (a bug)");
    }
    Ok(text)
}

/// The table `key` of `doc`, made if missing.
fn table<'d>(doc: &'d mut DocumentMut, key: &str) -> &'d mut Table {
    if !doc.contains_table(key) {
        doc[key] = Item::Table(Table::new());
    }
    doc[key]
        .as_table_mut()
        .expect("a table, made above if missing")
}

/// Measures `options.scene`'s game choices on `device` and writes the most accurate that
/// holds the target at `options.out`.
pub fn run(device: &Device, options: &TuneOptions) -> anyhow::Result<TuneReport> {
    let machine = Provenance::now(device);
    let sizes = RunSizes::new(device, options.quick);
    if let Some(frames) = options.target.frames() {
        // The scene as given is what every choice is weighed against: it must be measured.
        frames
            .keeps_game_time(options.scene.world.dt)
            .map_err(|why| anyhow::anyhow!("--fps for {}: {why}", options.scene_given))?;
    }
    let choices = selected(game_choices(&options.scene), &options.only)?;
    let mut bar = progress(choices.len() as u64, options.progress, "tune", "choices");
    // Said before anything is measured: the choices are warmed up and timed together before
    // the first is done, so a rate taken from the first would be far too slow.
    let rows = (0, choices.len(), 0);
    let framed = options.target.frames().is_some();
    bar.announce(estimate(
        device,
        (&options.scene, options.seed),
        &sizes,
        rows,
        framed,
    )?);
    let mut tick = |choice: &str| {
        bar.set_message(choice.to_owned());
        bar.inc(1);
    };
    let measure = Measure {
        audited: true,
        frames: options.target.frames(),
    };
    let rows = game_rows(device, &choices, options.seed, &sizes, measure, &mut tick)?;
    bar.finish_and_clear();
    let (chosen, rejected) =
        choose(&rows, options.target, options.margin).map_err(anyhow::Error::msg)?;
    let row = &rows[chosen];
    let target = options.target;
    let note = format!(
        "# Tuned by `gpuwars tune` from {} on {} ({}), {}: `{}`, {} for a target of {} {} \
         with a margin of {}%.\n",
        options.scene_given,
        machine.device,
        machine.backend,
        machine.date,
        row.choice,
        target.shown(target.rate(row)),
        figure(target.value()),
        target.unit(),
        figure(100.0 * options.margin),
    );
    let text = tuned_toml(&options.scene, &choices[chosen].1, &note)?;
    write_atomically(&options.out, text.as_bytes())?;
    Ok(TuneReport {
        machine,
        scene: options.scene_given.clone(),
        target: options.target,
        margin: options.margin,
        rows,
        chosen,
        rejected,
        out: shown(&options.out),
    })
}

impl TuneReport {
    /// What was chosen, what it costs against the scene as given, and why each other
    /// choice was not.
    pub fn to_text(&self) -> String {
        let row = &self.rows[self.chosen];
        let given = self.rows.iter().find(|r| r.choice == "default");
        let missed = |r: &GameRow| {
            let a = r.accuracy.as_ref();
            a.and_then(|a| a.missed)
                .map_or("–".to_owned(), |m| format!("{m:.1}"))
        };
        let kills = |r: &GameRow| {
            let a = r.accuracy.as_ref();
            a.and_then(|a| a.kills_per_shot)
                .map_or("–".to_owned(), |k| format!("{k:.2}"))
        };
        let target = self.target;
        let mut out = format!(
            "chosen:           {} for {} {} with {}% margin ({} needed in the slowest \
             round)\nspeed:            {} over the rounds\n",
            row.choice,
            figure(target.value()),
            target.unit(),
            figure(100.0 * self.margin),
            figure(needed(target.value(), self.margin)),
            target.shown(target.rate(row)),
        );
        if let Target::FramesPerSecond { size, .. } = target {
            out += &format!(
                "frames:           {}x{} pixels, each the steps due and the frame as `play` \
                 draws it; steps alone {}\n",
                size.0,
                size.1,
                rate_words(steps_rate(row), "steps/s")
            );
        }
        out += &format!(
            "contacts missed:  {} per thousand; kills per shot {}\n",
            missed(row),
            kills(row)
        );
        if let Some(g) = given.filter(|g| g.choice != row.choice) {
            out += &match &g.skipped {
                None => format!(
                    "as given:         {}, {} missed per thousand, kills per shot {}\n",
                    target.shown(target.rate(g)),
                    missed(g),
                    kills(g)
                ),
                Some(why) => format!("as given:         not measured: {why}\n"),
            };
        }
        out += &format!("written:          {}\n", self.out);
        for (i, why) in &self.rejected {
            out += &format!("rejected:         {}: {why}\n", self.rows[*i].choice);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::benchmark::tradeoff::GameAccuracy;

    /// A measured row: speed `(low, median, high)`, contacts missed and the mean depth.
    fn row(choice: &str, (low, median, high): (f64, f64, f64), missed: f64, depth: f64) -> GameRow {
        GameRow {
            choice: choice.into(),
            dt: 1.0 / 60.0,
            skipped: None,
            steps_per_s: median,
            steps_per_s_range: (low, high),
            sim_seconds_per_s: median / 60.0,
            accuracy: Some(GameAccuracy {
                steps: 100,
                expected: 50,
                tunnelling: 5,
                missed: Some(missed),
                extra: Some(0.0),
                wrong_partner: Some(0.0),
                late: Some(0.0),
                undecidable: 0,
                moment_undecidable: 0,
                shot_enemy: Some(missed),
                enemy_ship: None,
                body_wall: None,
                depth_mean: Some(depth),
                depth_max: depth,
                limit_violations: 0,
                kills_per_shot: Some(0.5),
            }),
            pareto: false,
            unseparated: Vec::new(),
            step_us: 1e6 / median,
            stages: String::new(),
            alive: 100,
            frames_per_s: None,
        }
    }

    fn table() -> Vec<GameRow> {
        let mut skipped = row("dt 1.2 s", (0.0, 0.0, 0.0), 0.0, 0.0);
        skipped.skipped = Some("does not apply".into());
        skipped.accuracy = None;
        vec![
            row("default", (90.0, 100.0, 110.0), 0.0, 3.0),
            row("4 substeps", (40.0, 45.0, 50.0), 0.0, 0.5),
            row("2 substeps", (70.0, 75.0, 80.0), 0.0, 1.5),
            row("nothing swept", (150.0, 160.0, 170.0), 250.0, 3.0),
            row("cap 8", (95.0, 120.0, 130.0), 200.0, 3.0),
            skipped,
        ]
    }

    #[test]
    fn the_most_accurate_choice_that_holds_the_target_is_chosen() {
        let rows = table();
        let pick = |target: f64| {
            choose(&rows, Target::StepsPerSecond(target), 0.2).map(|(i, _)| rows[i].choice.clone())
        };
        // Every choice holds 30 (36 needed): the shallowest contacts win.
        assert_eq!(pick(30.0).unwrap(), "4 substeps");
        // 50 needs 60 in the slowest round: 4 substeps' 40 is too slow.
        assert_eq!(pick(50.0).unwrap(), "2 substeps");
        // 70 needs 84: of the exact choices only the default holds it.
        assert_eq!(pick(70.0).unwrap(), "default");
        // 100 needs 120: only the choice that misses contacts holds it.
        assert_eq!(pick(100.0).unwrap(), "nothing swept");
        // A slowest round decides, not a median: cap 8's median of 120 does not hold 96.
        let (chosen, rejected) = choose(&rows, Target::StepsPerSecond(96.0), 0.0).unwrap();
        assert_eq!(rows[chosen].choice, "nothing swept");
        let why = |name: &str| {
            let i = rows.iter().position(|r| r.choice == name).unwrap();
            rejected.iter().find(|(j, _)| *j == i).unwrap().1.clone()
        };
        assert!(why("cap 8").contains("too slow"), "{}", why("cap 8"));
        assert!(why("dt 1.2 s").contains("not measured: does not apply"));
        let (_, rejected) = choose(&rows, Target::StepsPerSecond(30.0), 0.2).unwrap();
        let default = rejected.iter().find(|(i, _)| *i == 0).unwrap();
        assert!(default.1.contains("deeper"), "{}", default.1);
    }

    #[test]
    fn a_target_nothing_holds_is_refused_naming_the_fastest() {
        let rows = table();
        let e = choose(&rows, Target::StepsPerSecond(1000.0), 0.2).unwrap_err();
        assert!(
            e.contains("holds 1000 steps/s with its slowest round (1200 with the 20% margin)")
                && e.contains("`nothing swept`")
                && e.contains("160"),
            "{e}"
        );
        // Where none could be measured, the error says why for each.
        let none: Vec<GameRow> = rows.into_iter().filter(|r| r.skipped.is_some()).collect();
        let e = choose(&none, Target::StepsPerSecond(1.0), 0.0).unwrap_err();
        assert!(e.contains("could be measured"), "{e}");
        for r in &none {
            let why = format!("`{}`: {}", r.choice, r.skipped.as_ref().unwrap());
            assert!(e.contains(&why), "{e} lacks {why}");
        }
    }

    /// A frame rate is measured only where `play` keeps the game's time: up to 8 steps a
    /// frame (its most), not one more; the refusal says the lowest rate that is.
    #[test]
    fn a_frame_rate_below_plays_catch_up_is_refused() {
        // A step of 1/8 s: 1 frame a second is 8 steps.
        let at = |fps: f64| {
            FrameTiming {
                fps,
                size: (64, 64),
            }
            .keeps_game_time(0.125)
        };
        assert_eq!(at(1.0), Ok(()));
        assert_eq!(at(1000.0), Ok(()));
        let e = at(1.0 - 1e-9).unwrap_err();
        assert!(
            e.contains("more than the 8") && e.contains("aim at 1.00 frames/s"),
            "{e}"
        );
        let e = at(0.001).unwrap_err();
        assert!(e.contains("8000 steps"), "{e}");
    }

    /// A frame-rate target is held by the frames' slowest round, not the steps': a choice
    /// fast in steps but slow to draw (its frame plays many steps) is too slow for it.
    #[test]
    fn a_frame_rate_target_is_held_by_the_frames() {
        let mut rows = table();
        for (r, frames) in rows
            .iter_mut()
            .zip([(50.0, 55.0, 60.0), (58.0, 59.0, 60.0)])
        {
            r.frames_per_s = Some(Rate {
                low: frames.0,
                median: frames.1,
                high: frames.2,
            });
        }
        let fps = |fps: f64| Target::FramesPerSecond {
            fps,
            size: (1280, 720),
        };
        // 4 substeps holds 30 steps/s but draws 58 frames/s at worst: it holds 48 (57.6
        // needed), the default's 50 does not.
        let (chosen, rejected) = choose(&rows, fps(48.0), 0.2).unwrap();
        assert_eq!(rows[chosen].choice, "4 substeps");
        assert!(
            rejected[0].1.contains("ran 50.0 frames/s"),
            "{:?}",
            rejected[0]
        );
        // Rows without frames (not timed) hold no frame rate.
        let e = choose(&rows, fps(60.0), 0.2).unwrap_err();
        assert!(e.contains("`4 substeps`") && e.contains("frames/s"), "{e}");
    }

    /// `--choice` keeps the named choices and the scene as given, in the table's order;
    /// a name the scene lacks is refused naming the ones it has.
    #[test]
    fn only_the_named_choices_and_the_given_scene_are_measured() {
        let scene = Scene::load("paper").unwrap();
        let names = |only: &[&str]| {
            let only: Vec<String> = only.iter().map(|s| s.to_string()).collect();
            selected(game_choices(&scene), &only)
                .map(|c| c.into_iter().map(|(n, _)| n).collect::<Vec<_>>())
        };
        let all = names(&[]).unwrap();
        assert_eq!(all.len(), game_choices(&scene).len());
        assert_eq!(
            names(&["4 substeps", "dt 1/30, nothing swept"]).unwrap(),
            ["default", "4 substeps", "dt 1/30, nothing swept"]
        );
        assert_eq!(names(&["default"]).unwrap(), ["default"]);
        let e = names(&["4 substeps", "8 substeps"])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`8 substeps`") && e.contains("`2 substeps`") && e.contains("`cap 8`"),
            "{e}"
        );
    }

    /// Every game choice of each built-in game scene written into the scene's own text
    /// reads back as the choice (the function checks it), with the text's comments kept.
    #[test]
    fn a_tuned_scene_is_the_given_text_with_the_choice_written_in() {
        for name in ["paper", "arena", "kamikaze"] {
            let given = Scene::load(name).unwrap();
            for (label, tuned) in game_choices(&given) {
                let text = tuned_toml(&given, &tuned, "# tuned\n")
                    .unwrap_or_else(|e| panic!("{name} under {label}: {e:#}"));
                assert!(text.starts_with("# tuned\n"));
                let first_comment = given.source.lines().find(|l| l.starts_with('#')).unwrap();
                assert!(text.contains(first_comment), "{name} under {label}");
            }
        }
    }
}

//! [`Session`]: named models of any kind, a schedule of timed commands, the command log, and
//! undo/redo.
//!
//! # Time
//! Each model keeps its own clock and time step; [`Session::step`] advances every model by one
//! of its steps, [`Session::advance_to`] steps each model until its clock reaches a time.
//! Before a model steps, the scheduled commands addressed to it whose time `at` satisfies
//! `at <= t + dt / 2` are applied in time order (a scenario's timeline), then the model moves
//! its rope cursors and drops expired tools.
//!
//! # Undo
//! Every applied command is logged with the model's step count and time, and gets an undo
//! record ([`crate::model::Undo`]): an exact inverse where the mathematics gives one, always
//! with a snapshot of the state just before the command, so that undo after simulated time has
//! passed puts the model back as it was just before the command (its clock included). Redo
//! applies the undone command again to that state, which reproduces the state just after it.
//! A new command clears the redo list; a step does not (redo then applies the command at the
//! current time, so undo and redo work while a front end keeps the simulation running). A group
//! whose commands had steps between them (a drag) cannot be given back by applying its commands
//! again at once: its redo, with nothing in between since the undo, puts back the model exactly
//! as it was before the undo (a copy the undo keeps).
//! Scheduled commands that have fired are ordinary log entries: undoing one does not schedule
//! it again.
//!
//! # Undo groups
//! [`Session::begin_group`] and [`Session::end_group`] bracket the commands of one user action
//! (a rope drag: attach, many cursor moves, release); undo and redo treat them as one. Within a
//! group, a command whose undo record is a plain state snapshot adds no record of its own: the
//! group's earlier record, which puts the model back as it was before the group began, undoes
//! it too. So a drag of a thousand cursor moves keeps one snapshot, not a thousand. Redo of a
//! group applies its commands again one after the other (at the time undo went back to).

use serde::{Deserialize, Serialize};

use crate::command::{Command, Edit, EditError};
use crate::error::SessionError;
use crate::model::{Hit, Model, Ray, StepReport, Undo};
use vclay_core::Plasticity;

/// A command scheduled for a time (a scenario's timeline entry).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Timed {
    /// Time at which it applies.
    pub at: f64,
    /// The command.
    #[serde(flatten)]
    pub command: Command,
}

/// A command as applied.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LogEntry {
    /// The target model's step count when it was applied.
    pub step: u64,
    /// The target model's time when it was applied.
    pub time: f64,
    /// The model's name.
    pub model: String,
    /// The command (its `model` resolved).
    pub command: Command,
    /// What it did.
    pub message: String,
}

/// Borrowed parts of a session for saving: models by name, schedule, log.
pub(crate) type SessionParts<'a> = (Vec<(&'a str, &'a dyn Model)>, &'a [Timed], &'a [LogEntry]);

#[derive(Debug)]
struct UndoEntry {
    model: usize,
    undo: Undo,
    /// Log entries this record undoes (more than one when state-only commands of a group were
    /// merged into it).
    commands: usize,
    /// The undo group it belongs to.
    group: Option<u64>,
}

/// See `Session::redo_exact`.
#[derive(Debug)]
struct RedoExact {
    /// The model undone.
    model: usize,
    /// Its copy from before the undo.
    after: Box<dyn Model>,
    /// The session's revision and the model's step count just after the undo: if either moved,
    /// something happened since, and redo applies the commands again instead.
    revision: u64,
    steps: u64,
}

#[derive(Debug)]
struct Entry {
    name: String,
    model: Box<dyn Model>,
    /// Plastic flow after each step ([`Session::set_plasticity`]).
    plasticity: Option<Plasticity>,
}

/// Models of any kind, their commands and history (see the [module docs](self)).
#[derive(Debug, Default)]
pub struct Session {
    models: Vec<Entry>,
    schedule: Vec<Timed>,
    log: Vec<LogEntry>,
    undo: Vec<UndoEntry>,
    /// Undone commands, one list per undo step (a group, or one command), in applied order.
    redo: Vec<Vec<LogEntry>>,
    /// The model as it was before the last undo, while nothing has happened since: redo then
    /// puts it back exactly (a drag's deformation, which applying its commands again without
    /// the steps between them would not give).
    redo_exact: Option<RedoExact>,
    revision: u64,
    /// The open undo group and its nesting depth.
    group: Option<(u64, usize)>,
    next_group: u64,
}

impl Session {
    /// An empty session.
    pub fn new() -> Self {
        Self::default()
    }

    /// A session with one model.
    pub fn with_model(name: &str, model: Box<dyn Model>) -> Result<Self, SessionError> {
        let mut s = Self::new();
        s.add_model(name, model)?;
        Ok(s)
    }

    /// Adds a model; names are unique and non-empty.
    pub fn add_model(&mut self, name: &str, model: Box<dyn Model>) -> Result<(), SessionError> {
        if name.is_empty() || self.index(name).is_some() {
            return Err(SessionError::Model {
                model: name.to_string(),
                what: if name.is_empty() {
                    "a model name must not be empty".into()
                } else {
                    "a model of this name is already in the session".into()
                },
                source: None,
            });
        }
        self.models.push(Entry {
            name: name.to_string(),
            model,
            plasticity: None,
        });
        self.revision += 1;
        Ok(())
    }

    /// Names of the models, in order.
    pub fn model_names(&self) -> Vec<&str> {
        self.models.iter().map(|e| e.name.as_str()).collect()
    }

    /// Number of models.
    pub fn len(&self) -> usize {
        self.models.len()
    }

    /// Whether the session has no model.
    pub fn is_empty(&self) -> bool {
        self.models.is_empty()
    }

    fn index(&self, name: &str) -> Option<usize> {
        self.models.iter().position(|e| e.name == name)
    }

    fn resolve(&self, name: Option<&str>) -> Result<usize, SessionError> {
        match name {
            None if !self.models.is_empty() => Ok(0),
            None => Err(SessionError::NoSuchModel {
                name: "(first model)".into(),
                known: "no models".into(),
            }),
            Some(n) => self.index(n).ok_or_else(|| SessionError::NoSuchModel {
                name: n.to_string(),
                known: self.model_names().join(", "),
            }),
        }
    }

    /// The model named `name` (`None`: the first), read-only: display, pick, params, export.
    pub fn model(&self, name: Option<&str>) -> Result<&dyn Model, SessionError> {
        let i = self.resolve(name)?;
        Ok(self.models[i].model.as_ref())
    }

    /// A counter that grows with every change of any model (steps, commands, undo).
    pub fn revision(&self) -> u64 {
        self.revision + self.models.iter().map(|e| e.model.revision()).sum::<u64>()
    }

    /// Time of the session: the earliest model clock (0 without models).
    pub fn time(&self) -> f64 {
        self.models
            .iter()
            .map(|e| e.model.time())
            .reduce(f64::min)
            .unwrap_or(0.0)
    }

    /// The command log (what produced the current state from the initial models).
    pub fn log(&self) -> &[LogEntry] {
        &self.log
    }

    /// Commands scheduled and not yet applied.
    pub fn schedule(&self) -> &[Timed] {
        &self.schedule
    }

    /// Schedules commands (a scenario's timeline): each is checked now (model name, that the
    /// model takes it, its values) and not again when it fires; they apply in time order (ties
    /// in the given order) before the step that reaches `at`.
    pub fn schedule_commands(&mut self, timed: Vec<Timed>) -> Result<(), SessionError> {
        for (k, t) in timed.iter().enumerate() {
            let i = self.resolve(t.command.model.as_deref())?;
            let e = &self.models[i];
            if !(t.at.is_finite() && t.at >= 0.0) {
                return Err(SessionError::command(
                    t.command.edit.action(),
                    &e.name,
                    format!(
                        "scheduled entry {k}: `at` = {} must be >= 0 and finite",
                        t.at
                    ),
                ));
            }
            check_edit(e.model.as_ref(), &t.command.edit, t.at)
                .map_err(|r| SessionError::command(t.command.edit.action(), &e.name, r))?;
        }
        self.push_schedule(timed);
        Ok(())
    }

    /// Schedules commands already checked by [`check_edit`] (the scenario reader, which
    /// locates each error in its file).
    pub(crate) fn push_schedule(&mut self, timed: Vec<Timed>) {
        self.schedule.extend(timed);
        // Stable: equal times keep their order.
        self.schedule.sort_by(|a, b| a.at.total_cmp(&b.at));
    }

    /// Applies a command now; on error the session is unchanged.
    pub fn apply(&mut self, command: Command) -> Result<String, SessionError> {
        let i = self.resolve(command.model.as_deref())?;
        let msg = self.apply_to(i, command, false)?;
        self.redo.clear();
        self.redo_exact = None;
        Ok(msg)
    }

    /// Applies `command` to model `i`; `checked`: the command was checked when it was
    /// scheduled.
    fn apply_to(
        &mut self,
        i: usize,
        mut command: Command,
        checked: bool,
    ) -> Result<String, SessionError> {
        let e = &mut self.models[i];
        let name = e.name.clone();
        command.model = Some(name.clone());
        let edit = &command.edit;
        if !checked {
            check_edit(e.model.as_ref(), edit, e.model.time())
                .map_err(|r| SessionError::command(edit.action(), &name, r))?;
        }
        let (step, time) = (e.model.steps(), e.model.time());
        let applied = e
            .model
            .apply(edit)
            .map_err(|err| err.in_command(edit.action(), &name))?;
        let group = self.group.map(|g| g.0);
        let merge = group.is_some()
            && matches!(applied.undo, Undo::State(_))
            && self
                .undo
                .last()
                .is_some_and(|u| u.group == group && u.model == i);
        if merge {
            self.undo.last_mut().expect("checked").commands += 1;
        } else {
            self.undo.push(UndoEntry {
                model: i,
                undo: applied.undo,
                commands: 1,
                group,
            });
        }
        self.log.push(LogEntry {
            step,
            time,
            model: name,
            command,
            message: applied.message.clone(),
        });
        self.revision += 1;
        Ok(applied.message)
    }

    /// Opens an undo group (see the [module docs](self)); groups nest, the outermost counts.
    pub fn begin_group(&mut self) {
        match &mut self.group {
            Some((_, depth)) => *depth += 1,
            None => {
                self.next_group += 1;
                self.group = Some((self.next_group, 1));
            }
        }
    }

    /// Closes the innermost open undo group.
    pub fn end_group(&mut self) {
        if let Some((_, depth)) = &mut self.group {
            *depth -= 1;
            if *depth == 0 {
                self.group = None;
            }
        }
    }

    /// Undoes the last command, or the last undo group whole; returns the log entry of the
    /// first command undone (the one that began the group).
    pub fn undo(&mut self) -> Result<LogEntry, SessionError> {
        let last = self.undo.last().ok_or(SessionError::History("undo"))?;
        let group = last.group;
        let target = last.model;
        // The state before the undo, for an exact redo of a group (see `redo_exact`; a single
        // command redoes exactly by applying it again, and needs no copy).
        let after = group.map(|_| self.models[target].model.clone_model());
        let mut one_model = true;
        self.redo_exact = None;
        let mut undone: Vec<LogEntry> = Vec::new();
        loop {
            let Some(entry) = self.undo.pop() else { break };
            one_model &= entry.model == target;
            let k = self.log.len().saturating_sub(entry.commands);
            let logs: Vec<LogEntry> = self.log.drain(k..).collect();
            let name = logs.first().map_or(String::new(), |l| l.model.clone());
            let e = &mut self.models[entry.model];
            let r = match entry.undo {
                Undo::Model(m) => {
                    e.model = m;
                    Ok(())
                }
                u => e.model.undo(u),
            };
            self.revision += 1;
            undone.splice(0..0, logs);
            if let Err(err) = r {
                // What was undone so far stays undone (and redoable).
                if !undone.is_empty() {
                    self.redo.push(undone);
                }
                return Err(err.in_model(&name));
            }
            let more = group.is_some() && self.undo.last().is_some_and(|u| u.group == group);
            if !more {
                break;
            }
        }
        let first = undone
            .first()
            .cloned()
            .ok_or(SessionError::History("undo"))?;
        self.redo.push(undone);
        if let (true, Some(after)) = (one_model, after) {
            self.redo_exact = Some(RedoExact {
                model: target,
                after,
                revision: self.revision,
                steps: self.models[target].model.steps(),
            });
        }
        Ok(first)
    }

    /// Applies the last undone command (or group) again; returns its message (one line per
    /// command).
    pub fn redo(&mut self) -> Result<String, SessionError> {
        let logs = self.redo.pop().ok_or(SessionError::History("redo"))?;
        if let Some(x) = self.redo_exact.take() {
            let fresh =
                x.revision == self.revision && self.models[x.model].model.steps() == x.steps;
            let name = &self.models[x.model].name;
            // Only where applying the commands again cannot give the state back: steps ran
            // between them (a drag). A command, or commands of one instant, redo exactly anyway.
            let spans_steps = logs.first().map(|l| l.step) != logs.last().map(|l| l.step);
            if fresh && spans_steps && logs.iter().all(|l| &l.model == name) {
                return Ok(self.redo_exactly(x, logs));
            }
        }
        let grouped = logs.len() > 1;
        if grouped {
            self.begin_group();
        }
        let mut messages = Vec::with_capacity(logs.len());
        let mut result = Ok(());
        for (k, log) in logs.iter().enumerate() {
            let i = match self.resolve(Some(&log.model)) {
                Ok(i) => i,
                Err(e) => {
                    result = Err((k, e));
                    break;
                }
            };
            match self.apply_to(i, log.command.clone(), false) {
                Ok(m) => messages.push(m),
                Err(e) => {
                    result = Err((k, e));
                    break;
                }
            }
        }
        if grouped {
            self.end_group();
        }
        match result {
            Ok(()) => Ok(messages.join("\n")),
            Err((k, e)) => {
                // The commands not applied stay redoable.
                self.redo.push(logs[k..].to_vec());
                Err(e)
            }
        }
    }

    /// Redo when nothing happened since the undo: the model as it was before the undo comes
    /// back bit for bit (a drag's deformation included), and its undo record is the model undone.
    fn redo_exactly(&mut self, x: RedoExact, logs: Vec<LogEntry>) -> String {
        let before = std::mem::replace(&mut self.models[x.model].model, x.after);
        let message = logs
            .iter()
            .map(|l| l.message.as_str())
            .collect::<Vec<_>>()
            .join("\n");
        // Still a group (of one record), so that its undo keeps a copy for the next redo.
        self.next_group += 1;
        self.undo.push(UndoEntry {
            model: x.model,
            undo: Undo::Model(before),
            commands: logs.len(),
            group: Some(self.next_group),
        });
        self.log.extend(logs);
        self.revision += 1;
        message
    }

    /// Whether there is something to undo / redo.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }
    /// See [`Session::can_undo`].
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Applies the scheduled commands due for model `i`; returns their log lines.
    fn apply_due(&mut self, i: usize) -> Result<Vec<String>, SessionError> {
        let mut lines = Vec::new();
        loop {
            let (t, dt) = (self.models[i].model.time(), self.models[i].model.dt());
            let name = &self.models[i].name;
            let pos = self.schedule.iter().position(|s| {
                s.command.model.as_deref().map_or(i == 0, |m| m == name) && s.at <= t + 0.5 * dt
            });
            let Some(k) = pos else { break };
            let timed = self.schedule.remove(k);
            let msg = self.apply_to(i, timed.command, true)?;
            lines.push(format!("t = {t:.4}: {msg}"));
        }
        Ok(lines)
    }

    fn step_model(
        &mut self,
        i: usize,
        lines: &mut Vec<String>,
    ) -> Result<StepReport, SessionError> {
        lines.extend(self.apply_due(i)?);
        let e = &mut self.models[i];
        let report = e.model.step().map_err(|err| err.in_model(&e.name))?;
        if let Some(p) = e.plasticity {
            e.model
                .plastic_flow(p.fraction(e.model.dt()), p.yield_distance)
                .map_err(|err| err.in_model(&e.name))?;
        }
        Ok(report)
    }

    /// Sets the plastic flow of model `name` (the first when `None`): after each of its steps
    /// the rest shape follows the shape where it is displaced past `yield_distance`, at `rate`
    /// (`vclay_core::plasticity`; the studio's sculpt mode). `None` turns it off (the papers'
    /// elastic clay). A setting of the session, saved in session files, not an undo step; what
    /// the flow did to the rest shape is undone with the steps that did it.
    ///
    /// # Errors
    /// An unknown model, or a kind without a rest shape to flow (FFD, PDE, D-NURBS with frozen
    /// weights).
    pub fn set_plasticity(
        &mut self,
        name: Option<&str>,
        plasticity: Option<Plasticity>,
    ) -> Result<(), SessionError> {
        let i = self.resolve(name)?;
        let e = &mut self.models[i];
        if let Some(p) = plasticity {
            // A flow of fraction 0 changes nothing and fails where the kind has none.
            e.model
                .plastic_flow(0.0, p.yield_distance)
                .map_err(|err| err.in_model(&e.name))?;
        }
        e.plasticity = plasticity;
        Ok(())
    }

    /// The plastic flow of model `name` (the first when `None`), if set.
    pub fn plasticity(&self, name: Option<&str>) -> Option<Plasticity> {
        self.resolve(name)
            .ok()
            .and_then(|i| self.models[i].plasticity)
    }

    /// Advances every model by one step; returns one report per model and the log lines of
    /// the scheduled commands applied.
    pub fn step(&mut self) -> Result<(Vec<StepReport>, Vec<String>), SessionError> {
        let mut lines = Vec::new();
        let mut reports = Vec::with_capacity(self.models.len());
        for i in 0..self.models.len() {
            reports.push(self.step_model(i, &mut lines)?);
        }
        Ok((reports, lines))
    }

    /// Advances every model by `n` steps.
    pub fn run(&mut self, n: u64) -> Result<Vec<String>, SessionError> {
        let mut lines = Vec::new();
        for _ in 0..n {
            lines.extend(self.step()?.1);
        }
        Ok(lines)
    }

    /// Steps each model until its clock is within half a step of `t`.
    pub fn advance_to(&mut self, t: f64) -> Result<Vec<String>, SessionError> {
        let mut lines = Vec::new();
        for i in 0..self.models.len() {
            while self.models[i].model.time() + 0.5 * self.models[i].model.dt() < t {
                self.step_model(i, &mut lines)?;
            }
        }
        Ok(lines)
    }

    /// One step of [`Session::advance_to`]: a step of the first model whose clock is more
    /// than half a step before `t`, with the log lines of the scheduled commands it applied;
    /// `None` when every model has reached `t`. Calling it until `None` is `advance_to(t)`
    /// step for step, so a front end can stop in between (the Python module checks Ctrl-C).
    pub fn advance_step(&mut self, t: f64) -> Result<Option<Vec<String>>, SessionError> {
        let Some(i) = (0..self.models.len())
            .find(|&i| self.models[i].model.time() + 0.5 * self.models[i].model.dt() < t)
        else {
            return Ok(None);
        };
        let mut lines = Vec::new();
        self.step_model(i, &mut lines)?;
        Ok(Some(lines))
    }

    /// The nearest hit of `ray` on any model within `tolerance`: `(model name, hit)`.
    pub fn pick(&self, ray: &Ray, tolerance: f64) -> Option<(String, Hit)> {
        if !(crate::pick::valid_ray(ray) && tolerance.is_finite() && tolerance >= 0.0) {
            return None;
        }
        self.models
            .iter()
            .filter_map(|e| e.model.pick(ray, tolerance).map(|h| (e.name.clone(), h)))
            .min_by(|a, b| a.1.distance.total_cmp(&b.1.distance))
    }

    /// Applies the due scheduled commands of every model without stepping (used before
    /// writing the first frame of a run).
    pub fn apply_due_now(&mut self) -> Result<Vec<String>, SessionError> {
        let mut lines = Vec::new();
        for i in 0..self.models.len() {
            lines.extend(self.apply_due(i)?);
        }
        Ok(lines)
    }

    pub(crate) fn parts(&self) -> SessionParts<'_> {
        (
            self.models
                .iter()
                .map(|e| (e.name.as_str(), e.model.as_ref()))
                .collect(),
            &self.schedule,
            &self.log,
        )
    }

    pub(crate) fn set_history(&mut self, schedule: Vec<Timed>, log: Vec<LogEntry>) {
        self.schedule = schedule;
        self.log = log;
    }
}

/// Why `model` cannot take `edit` at time `at`: an action its kind does not take
/// ([`Model::accepts`]), or invalid values ([`Edit::validate`]). The one check every path runs
/// once (a command applied now, a scheduled one when it is scheduled).
pub(crate) fn check_edit(model: &dyn Model, edit: &Edit, at: f64) -> Result<(), EditError> {
    if !model.accepts(edit) {
        let takes: Vec<&str> = model.tools().iter().map(|t| t.action).collect();
        // The kind takes it, this model's setup does not (a D-NURBS on the frozen engine).
        let setup = if crate::describe::actions(model.kind()).contains(&edit.action()) {
            " with its settings (see its `engine`)"
        } else {
            ""
        };
        return Err(EditError::new(
            "action",
            format!(
                "a {} model does not take `{}`{setup}; it takes {}",
                model.kind(),
                edit.action(),
                takes.join(", ")
            ),
        ));
    }
    edit.validate(at)
}

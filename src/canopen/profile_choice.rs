//! Which vendor profile decodes each node's EMCY frames, and why: a
//! `--profile NODE=NAME` flag, a `--profile NAME` flag, a `--profile-file`,
//! the node's identity as the trace shows it (SDO uploads of 0x1000 and
//! 0x1018 sub 1), or the default, in that order.

use std::collections::HashMap;
use std::path::PathBuf;

use super::NodeId;
use super::profile::{self, Profile};
use super::sdo::{self, Object};

/// A profile asked for by name: for every node (`--profile NAME`) or for
/// one (`--profile NODE=NAME`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProfileRequest {
    /// The node it is for; `None` for every node.
    pub node: Option<NodeId>,
    /// A built-in profile's name or a user profile's.
    pub name: String,
}

/// Why a node got its profile (the `profile_source` key).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProfileSource {
    Flag,
    File,
    Trace,
    Default,
}

impl ProfileSource {
    pub fn slug(self) -> &'static str {
        match self {
            ProfileSource::Flag => "flag",
            ProfileSource::File => "file",
            ProfileSource::Trace => "trace",
            ProfileSource::Default => "default",
        }
    }
}

/// A node's profile and why it got it.
#[derive(Clone, Copy, Debug)]
pub struct Chosen {
    pub profile: &'static Profile,
    pub source: ProfileSource,
}

/// What the command line chose.
#[derive(Clone, Debug, Default)]
pub struct ProfileChoice {
    /// `--profile NODE=NAME`.
    pub nodes: Vec<(NodeId, &'static Profile)>,
    /// `--profile NAME`: every node not named above.
    pub all: Option<&'static Profile>,
    /// `--profile-file FILE` not named by a `--profile` flag: every node not
    /// chosen by a flag.
    pub file: Option<&'static Profile>,
}

/// What a node's SDO answers said about it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Identity {
    device_type: Option<u32>,
    vendor_id: Option<u32>,
}

/// Per-node profiles for one input.
#[derive(Debug)]
pub struct NodeProfiles<'c> {
    choice: &'c ProfileChoice,
    default: &'static Profile,
    identity: HashMap<NodeId, Identity>,
    /// The profile the identity selects, with the reason, per node id.
    from_trace: HashMap<NodeId, (&'static Profile, String)>,
}

impl<'c> NodeProfiles<'c> {
    pub fn new(choice: &'c ProfileChoice) -> Self {
        NodeProfiles {
            choice,
            default: default_profile(),
            identity: HashMap::new(),
            from_trace: HashMap::new(),
        }
    }

    pub fn get(&self, node: NodeId) -> Chosen {
        let flag = |profile| Chosen {
            profile,
            source: ProfileSource::Flag,
        };
        if let Some(&(_, p)) = self.choice.nodes.iter().find(|(n, _)| *n == node) {
            return flag(p);
        }
        if let Some(p) = self.choice.all {
            return flag(p);
        }
        if let Some(p) = self.choice.file {
            return Chosen {
                profile: p,
                source: ProfileSource::File,
            };
        }
        // Most traces show no identity: no hashing per EMCY then.
        if !self.from_trace.is_empty()
            && let Some((p, _)) = self.from_trace.get(&node)
        {
            return Chosen {
                profile: p,
                source: ProfileSource::Trace,
            };
        }
        Chosen {
            profile: self.default,
            source: ProfileSource::Default,
        }
    }

    /// Why the trace chose the node's profile ("vendor id 0x... (...)"), when
    /// it did and nothing on the command line overrode it.
    pub fn reason(&self, node: NodeId) -> Option<&str> {
        if self.get(node).source != ProfileSource::Trace {
            return None;
        }
        self.from_trace.get(&node).map(|(_, r)| r.as_str())
    }

    /// The node's device type (0x1000), as the trace or its DCF showed it.
    pub fn device_type(&self, node: NodeId) -> Option<u32> {
        if self.identity.is_empty() {
            return None;
        }
        self.identity.get(&node)?.device_type
    }

    /// A value the node holds (SDO upload or confirmed download): device
    /// type and vendor id choose its profile.
    pub fn object_value(&mut self, node: NodeId, object: Object, value: u32) {
        if !matches!(
            (object.index, object.sub),
            (sdo::DEVICE_TYPE, 0) | (sdo::IDENTITY, 1)
        ) {
            return;
        }
        // Only nodes whose identity the trace shows get an entry: a map,
        // as node ids go up to 65535 (EtherCAT station addresses).
        let id = self.identity.entry(node).or_default();
        match object.index {
            sdo::DEVICE_TYPE => id.device_type = Some(value),
            _ => id.vendor_id = Some(value),
        }
        match profile::for_identity(id.device_type, id.vendor_id) {
            Some(chosen) => self.from_trace.insert(node, chosen),
            None => self.from_trace.remove(&node),
        };
    }
}

/// Turns `--profile` and `--profile-file` into a choice. User profiles are
/// loaded once for the whole run (they live as long as the process). A name
/// is looked up among the user profiles first, then the built-ins.
pub fn resolve(args: &[ProfileRequest], files: &[PathBuf]) -> anyhow::Result<ProfileChoice> {
    let mut user: Vec<&'static Profile> = Vec::new();
    for f in files {
        let p = Profile::load(f)?;
        user.push(Box::leak(Box::new(p)));
    }
    let find = |name: &str| -> anyhow::Result<&'static Profile> {
        user.iter()
            .copied()
            .find(|p| p.name() == name)
            .or_else(|| Profile::builtin(name))
            .ok_or_else(|| {
                let known: Vec<&str> = user
                    .iter()
                    .map(|p| p.name())
                    .chain(Profile::builtins().iter().map(Profile::name))
                    .collect();
                anyhow::anyhow!("unknown profile '{name}' (known: {})", known.join(", "))
            })
    };
    let mut choice = ProfileChoice::default();
    for a in args {
        let p = find(&a.name)?;
        match a.node {
            Some(node) => {
                choice.nodes.retain(|(n, _)| *n != node);
                choice.nodes.push((node, p));
            }
            None => choice.all = Some(p),
        }
    }
    let named = |p: &Profile| args.iter().any(|a| a.name == p.name());
    let unnamed: Vec<&'static Profile> = user.iter().copied().filter(|p| !named(p)).collect();
    match unnamed.as_slice() {
        [] => {}
        [one] => choice.file = Some(one),
        _ => anyhow::bail!(
            "several --profile-file profiles ({}) and no --profile NODE=NAME saying which \
             node uses which",
            unnamed
                .iter()
                .map(|p| p.name())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
    Ok(choice)
}

/// The profile nodes get when nothing chooses one.
pub fn default_profile() -> &'static Profile {
    match Profile::builtin(profile::DEFAULT_PROFILE) {
        Some(p) => p,
        // The built-in set always holds the default; a test pins it.
        None => &Profile::builtins()[0],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn named(name: &str) -> &'static Profile {
        Profile::builtin(name).unwrap()
    }

    const DEVICE_TYPE: Object = Object {
        index: 0x1000,
        sub: 0,
    };

    #[test]
    fn the_default_profile_exists() {
        assert_eq!(default_profile().name(), profile::DEFAULT_PROFILE);
    }

    #[test]
    fn precedence_node_flag_then_all_flag_then_file_then_trace_then_default() {
        let mut choice = ProfileChoice::default();
        let pick = |c: &ProfileChoice, node| {
            let mut p = NodeProfiles::new(c);
            p.object_value(2, DEVICE_TYPE, 0x0002_0192);
            let chosen = p.get(node);
            (chosen.profile.name().to_string(), chosen.source)
        };
        assert_eq!(pick(&choice, 1), ("cia402".into(), ProfileSource::Default));
        assert_eq!(pick(&choice, 2).1, ProfileSource::Trace);
        choice.file = Some(named("cia301"));
        assert_eq!(pick(&choice, 2), ("cia301".into(), ProfileSource::File));
        choice.all = Some(named("canopennode"));
        assert_eq!(
            pick(&choice, 2),
            ("canopennode".into(), ProfileSource::Flag)
        );
        choice.nodes.push((2, named("cia402")));
        assert_eq!(pick(&choice, 2), ("cia402".into(), ProfileSource::Flag));
        assert_eq!(
            pick(&choice, 3),
            ("canopennode".into(), ProfileSource::Flag)
        );
    }

    fn arg(node: Option<NodeId>, name: &str) -> ProfileRequest {
        ProfileRequest {
            node,
            name: name.to_string(),
        }
    }

    #[test]
    fn resolve_flags() {
        let c = resolve(
            &[
                arg(None, "cia301"),
                arg(Some(5), "canopennode"),
                arg(Some(5), "cia402"),
            ],
            &[],
        )
        .unwrap();
        assert_eq!(c.all.map(Profile::name), Some("cia301"));
        let nodes: Vec<(NodeId, &str)> = c.nodes.iter().map(|(n, p)| (*n, p.name())).collect();
        assert_eq!(nodes, [(5, "cia402")], "the last flag for a node wins");
        assert!(c.file.is_none());
        let err = resolve(&[arg(None, "nope")], &[]).unwrap_err().to_string();
        assert!(err.contains("unknown profile 'nope'"), "{err}");
        assert!(err.contains("cia402"), "lists the known names: {err}");
    }

    #[test]
    fn only_identity_objects_count_and_bad_nodes_are_ignored() {
        let choice = ProfileChoice::default();
        let mut p = NodeProfiles::new(&choice);
        p.object_value(
            5,
            Object {
                index: 0x1000,
                sub: 1,
            },
            402,
        );
        assert_eq!(p.get(5).source, ProfileSource::Default);
        p.object_value(200, DEVICE_TYPE, 402);
        p.object_value(5, DEVICE_TYPE, 402);
        assert_eq!(p.get(5).source, ProfileSource::Trace);
        assert!(p.reason(5).is_some());
        assert_eq!(p.reason(6), None);
    }
}

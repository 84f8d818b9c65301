//! `--format html`: one self-contained page (no network, no external
//! scripts, fonts or images; opens from disk) with the timeline chart of each
//! input and its events table below, filterable by node and sortable by
//! column. The chart is the SVG of [`super::chart`], inlined.
//!
//! The table is bounded: a page carries at most [`PAGE_ROWS`] events of
//! each input. Past that it carries every 2nd, then every 4th event (and so
//! on), so that its rows still cover the whole trace and the table follows
//! a zoom anywhere in it; a note says so (the chart still draws every
//! event; `--format table` or `ndjson` list every event).

use super::format::codes_list;
use std::fmt::Write as _;
use std::io::{self, Write};

use super::chart::{self, Clock, Collector, Panel, esc};
use super::svg::{doc_title, document, style_sheet};
use super::table::health_description;
use super::timefmt::TimeFormat;
use crate::analyze::{
    BootEvent, BusEvent, Diagnostic, EmcyEvent, Health, HealthEvent, InputReport, Sink,
};
use crate::canopen::NodeId;
use crate::canopen::profile::{Decoded, FieldValue};
use crate::timeline::At;
use crate::trace::Timestamp;

/// Events a page carries per input. A row is some 400 bytes of HTML, so a
/// page stays below about 4 MB an input however long the trace: the size
/// a browser opens and filters without a pause.
pub const PAGE_ROWS: usize = 10_000;

/// What a row of the events table is.
enum Kind {
    /// An EMCY frame with its error code.
    Emcy(u16),
    Boot,
    /// A node-health event: its JSON `type` (`nmt`, `heartbeat_lost`, ...).
    Health(&'static str),
}

/// One row of the events table, kept until the input ends (the time
/// column's format depends on the whole input's span).
struct Row {
    time: Option<Timestamp>,
    line: u64,
    channel: String,
    node: NodeId,
    kind: Kind,
    register: u8,
    transition: Option<u8>,
    description: String,
    /// The manufacturer bytes as the profile reads them (the vendor's fault
    /// code, category), else the bytes themselves when not all zero.
    manufacturer: String,
    /// `(tag, text)` of each warning.
    warnings: Vec<(&'static str, String)>,
    cleared: Vec<u16>,
    state: &'static str,
}

/// A health event's description: the table's and CSV's words (times in
/// ISO-8601), and a read-out's entries, which the table lists on lines of
/// their own.
fn health_text(health: &Health) -> String {
    let mut text = health_description(health, &TimeFormat::default());
    if let Health::ErrorHistory(h) = health {
        for (i, e) in h.entries.iter().enumerate() {
            text.push_str(if i == 0 { ": " } else { "; " });
            let _ = write!(text, "0x{:04X} {}", e.code, e.description);
            if e.info != 0 {
                let _ = write!(text, " (info 0x{:04X})", e.info);
            }
            if e.before_trace {
                text.push_str(", before the trace");
            }
        }
    }
    text
}

/// The manufacturer cell: `category: 1 (cleared only by a reset); ...`
/// from the profile's fields (a `_text` field joins its number), else the
/// raw bytes 3-7.
fn manufacturer_cell(decoded: Option<&Decoded>, data: &[u8]) -> String {
    let Some(d) = decoded else {
        let raw = data.get(3..).unwrap_or_default();
        if raw.iter().all(|&b| b == 0) {
            return String::new();
        }
        return raw.iter().fold(String::new(), |mut s, b| {
            let _ = write!(s, "{b:02X}");
            s
        });
    };
    let mut parts: Vec<String> = Vec::with_capacity(d.fields.len());
    for (key, value) in &d.fields {
        let text = match value {
            FieldValue::Int(n) => n.to_string(),
            FieldValue::Text(t) => t.clone(),
        };
        // `category_text` after `category`: one item, `category: 1 (text)`.
        if let Some(base) = key.strip_suffix("_text")
            && let Some(last) = parts.last_mut()
            && last.starts_with(&format!("{base}: "))
        {
            let _ = write!(last, " ({text})");
            continue;
        }
        parts.push(format!("{key}: {text}"));
    }
    parts.join("; ")
}

struct Section {
    panel: Panel,
    rows: Vec<Row>,
    events: u64,
    /// The page carries every `stride`-th event (1: all of them).
    stride: u64,
}

pub struct HtmlReport<W: Write> {
    out: W,
    collector: Collector,
    /// Events `0, stride, 2 * stride, ...` of the input so far.
    rows: Vec<Row>,
    events: u64,
    stride: u64,
    sections: Vec<Section>,
}

impl<W: Write> HtmlReport<W> {
    pub fn new(out: W) -> Self {
        HtmlReport {
            out,
            collector: Collector::default(),
            rows: Vec::new(),
            events: 0,
            stride: 1,
            sections: Vec::new(),
        }
    }

    /// Keeps every `stride`-th event. When [`PAGE_ROWS`] are kept, every
    /// other one is dropped and the stride doubles: the rows stay evenly
    /// spread over the input's events, in bounded memory, without knowing
    /// in advance how many will come.
    fn keep(&mut self, row: impl FnOnce() -> Row) {
        let index = self.events;
        self.events += 1;
        if !index.is_multiple_of(self.stride) {
            return;
        }
        if self.rows.len() >= PAGE_ROWS {
            let mut i = 0usize;
            self.rows.retain(|_| {
                i += 1;
                i % 2 == 1
            });
            self.stride *= 2;
            if !index.is_multiple_of(self.stride) {
                return;
            }
        }
        self.rows.push(row());
    }
}

const PAGE_STYLE: &str = "\
body{font:14px system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;margin:16px;color:#222;background:#fff}
h1{font-size:20px;margin:0 0 12px}
h2{font-size:16px;margin:18px 0 6px}
section.input{margin-bottom:36px}
.chart{overflow-x:auto}
.chart svg{display:block}
.ec g.lane{cursor:pointer}
table.ev{border-collapse:collapse;font-size:12px;max-width:100%}
table.ev th{background:#eceef1;text-align:left;padding:4px 8px;cursor:pointer;position:sticky;top:0;user-select:none}
table.ev th[data-dir=asc]::after{content:' \\25B2'}
table.ev th[data-dir=desc]::after{content:' \\25BC'}
table.ev td{padding:2px 8px;border-bottom:1px solid #eee;overflow-wrap:anywhere}
table.ev td.n{text-align:right;font-variant-numeric:tabular-nums}
table.ev td.t{min-width:8em;max-width:36em}
@media (max-width:760px){table.ev,table.ev thead,table.ev tbody,table.ev tr{display:block}table.ev th,table.ev td{display:inline-block;border:0}table.ev tr{border-bottom:1px solid #ddd;padding:2px 0}table.ev th{position:static}table.ev tr[hidden]{display:none}}
table.ev tr.boot td{color:#2c4f9e}
table.ev tr.reset td{color:#1b7837}
table.ev tr.nmt td,table.ev tr.error_history td,table.ev tr.error_history_cleared td{color:#555}
table.ev tr.heartbeat_lost td{color:#b2182b;font-weight:600}
table.ev tr.heartbeat_back td{color:#1b7837}
table.ev tr.sdo_abort td{color:#a6611a}
table.ev td.w{color:#a6611a}
.note{color:#555}
p.zoom{margin:0 0 6px}
p.zoom button{margin-right:4px;min-width:2em}
button.prev,button.next{margin-left:6px}
";

/// The page's behaviour, plain DOM and no library (the page works without
/// it, as the static chart and the whole table):
/// - the chart fills the window: the time scale is re-laid from the panel's
///   `data-*` (plot edges, scale values there, the scale's kind and origin), bars
///   and markers move, labels appear on bars wide enough, ticks are redrawn
///   as the Rust side draws them, the legend re-flows;
/// - wheel zooms around the pointer, drag pans, double-click or the
///   buttons go back; the events table then lists the rows in the visible
///   range only (`data-v`: each row's value on the time scale);
/// - filter by node (select, or a click on a lane) and sort by a column;
/// - more than 1,000 rows are shown a page of 1,000 at a time, with buttons
///   to turn the pages.
///
/// The script's comments are part of every page and of the golden files:
/// its `axis.rs, tick_label` names what is now `chart/time_scale.rs`.
const SCRIPT: &str = r#"document.querySelectorAll('section.input').forEach(function(sec){
var box=sec.querySelector('.chart'),svg=box.querySelector('svg'),p=svg.querySelector('g.panel'),tb=sec.querySelector('tbody'),sel=sec.querySelector('select'),shown=sec.querySelector('.shown');
var view=null,all=null,drag=null,moved=false,W=0,X0=0,X1=0,fit=null;
// A panel without lanes has no axis to zoom.
if(p&&p.querySelector('line.axis')){
var d=p.dataset;X0=+d.x0;var B1=+d.x1,lo=+d.lo,hi=+d.hi,ax=d.axis,base=+d.base,oneday=d.oneday==='1';
all=[lo,hi];view=all.slice();
function val(x){return lo+(x-X0)/(B1-X0)*(hi-lo);}
function px(v){return X0+(v-view[0])/(view[1]-view[0])*(X1-X0);}
// The drawn geometry in axis values, read once.
var items=[];
p.querySelectorAll('g.lane rect,g.lane line,g.lane circle,g.lane path,line.end').forEach(function(e){
var t=e.tagName,g=function(a){return +e.getAttribute(a);};
if(t==='rect')items.push([e,0,val(g('x')),val(g('x')+g('width'))]);
else if(t==='line')items.push([e,1,val(g('x1')),val(g('x2'))]);
else if(t==='circle')items.push([e,2,val(g('cx'))]);
else{var m=/^M(-?[\d.]+)/.exec(e.getAttribute('d'));if(m)items.push([e,3,val(+m[1]),+m[1]]);}});
var bars=[].slice.call(p.querySelectorAll('g.lane rect.b')),dark={};
function isDark(r){var c=r.getAttribute('class');if(!(c in dark)){var m=/(\d+)\D+(\d+)\D+(\d+)/.exec(getComputedStyle(r).fill)||[0,255,255,255];dark[c]=.2126*m[1]+.7152*m[2]+.0722*m[3]<110;}return dark[c];}
var SVGNS=svg.namespaceURI,axl=p.querySelector('line.axis'),ay=+axl.getAttribute('y1'),ticks=p.querySelector('g.ticks'),cap=p.querySelector('text.cap');
var WALL=[1e-6,2e-6,5e-6,1e-5,2e-5,5e-5,1e-4,2e-4,5e-4,1e-3,2e-3,5e-3,.01,.02,.05,.1,.2,.5,1,2,5,10,15,30,60,120,300,600,900,1800,3600,7200,10800,21600,43200,86400];
function nice(r){var m=Math.pow(10,Math.floor(Math.log10(r)));return [1,2,5,10].map(function(k){return k*m;}).filter(function(s){return s>=r*(1-1e-9);})[0];}
function step(span){var r=span/((X1-X0)/90);if(!(r>0))return 1;if(ax==='lines')return Math.max(1,nice(r));if(ax==='seconds')return nice(r);
for(var i=0;i<WALL.length;i++)if(WALL[i]>=r)return WALL[i];return 86400*nice(r/86400);}
function decs(s){var d=0;while(d<9&&Math.abs(s*Math.pow(10,d)-Math.round(s*Math.pow(10,d)))>1e-6)d++;return d;}
// A tick's label, as the Rust side writes them (axis.rs, tick_label).
function label(abs,s){var d=decs(s);if(ax==='lines')return abs.toFixed(0);if(ax==='seconds')return abs.toFixed(d);
var per=Math.pow(10,d),u=Math.round(abs*per),sec=Math.floor(u/per),f=String(u-sec*per),iso=utc(sec);if(!iso)return abs.toFixed(d);
while(f.length<d)f='0'+f;var md=iso.slice(5,10),hm=iso.slice(11,16),hms=iso.slice(11,19);
return s>=86400?md:!oneday?md+' '+hm:s>=60?hm:d===0?hms:hms+'.'+f;}
// ISO-8601 of a Unix time, or null past the years a Date holds (a trace's
// times can be any 64-bit number; the Rust side draws them all).
function utc(t){var d=new Date(Math.floor(t*1000));return isNaN(d.getTime())?null:d.toISOString();}
function el(t,a,txt){var e=document.createElementNS(SVGNS,t);for(var k in a)e.setAttribute(k,a[k]);if(txt)e.textContent=txt;return e;}
function clampRect(e,a,b){var x=Math.max(px(a),X0-1),y=Math.min(px(b),X1+8);e.style.display=y<X0-1||x>X1+8?'none':'';e.setAttribute('x',x.toFixed(1));e.setAttribute('width',Math.max(y-x,1).toFixed(1));}
function layout(){
W=Math.max(320,box.clientWidth);X1=W-(960-B1);
svg.setAttribute('width',W);
// Title and subtitle cut to the width, the whole text in a tooltip.
p.querySelectorAll('text.t1,text.t2').forEach(function(t){var n=t.firstChild;if(!n||n.nodeType!==3)return;
if(!t.hasAttribute('data-full')){t.setAttribute('data-full',n.nodeValue);t.appendChild(el('title',{},n.nodeValue));}
var s=t.getAttribute('data-full'),room=W-(+t.getAttribute('x'))-8;n.nodeValue=s;
while(s.length>1&&t.getComputedTextLength()>room){s=s.slice(0,-1);n.nodeValue=s+'\u2026';}});
p.querySelectorAll('rect.bg').forEach(function(r){r.setAttribute('width',W);});
axl.setAttribute('x2',X1);cap.setAttribute('x',X1);
items.forEach(function(it){var e=it[0];
if(it[1]===0)clampRect(e,it[2],it[3]);
else{var x=px(it[2]),out=x<X0-1||x>X1+9;e.style.display=out?'none':'';
if(it[1]===1){e.setAttribute('x1',x.toFixed(1));e.setAttribute('x2',px(it[3]).toFixed(1));}
else if(it[1]===2)e.setAttribute('cx',x.toFixed(1));
else e.setAttribute('transform','translate('+(x-it[3]).toFixed(1)+',0)');}});
// Labels where bars are now wide enough (0.6 em of 9 px a character).
p.querySelectorAll('text.bl').forEach(function(t){t.remove();});
bars.forEach(function(r){if(r.style.display==='none')return;var w=+r.getAttribute('width'),c=r.getAttribute('data-c')||'',s=c.slice(2,6);
var l=[c,s].filter(function(t){return t&&t.length*5.4+4<=w;})[0];if(!l)return;
r.parentNode.insertBefore(el('text',{'class':isDark(r)?'bl w':'bl',x:(+r.getAttribute('x')+2).toFixed(1),y:(+r.getAttribute('y')+7.5).toFixed(1)},l),r.nextSibling);});
ticks.textContent='';var s=step(view[1]-view[0]),abs=Math.ceil((base+view[0])/s)*s;
for(var i=0;i<200&&abs-base<=view[1]+s*1e-6;i++,abs=Math.ceil((base+view[0])/s)*s+i*s){var x=px(abs-base).toFixed(1);
ticks.appendChild(el('line',{'class':'grid',x1:x,y1:52,x2:x,y2:ay+4}));ticks.appendChild(el('text',{'class':'tick',x:x,y:ay+16},label(abs,s)));}
// The legend, re-flowed to the width.
var lx=10,ly=null;p.querySelectorAll('g.legend>g').forEach(function(g){var m=/,([-\d.]+)\)/.exec(g.getAttribute('transform'));if(ly===null)ly=+m[1];
var w=g.getBBox().width+14;if(lx>10&&(g.classList.contains('r')||lx+w>W-10)){lx=10;ly+=18;}g.setAttribute('transform','translate('+lx.toFixed(1)+','+ly+')');lx+=w;});
var h=ly===null?+svg.getAttribute('height'):ly+18;svg.setAttribute('height',h);svg.setAttribute('viewBox','0 0 '+W+' '+h);
var z=view[0]>all[0]||view[1]<all[1];sec.setAttribute('data-view',view[0]+' '+view[1]);
range.textContent=z?'showing '+when(view[0])+' – '+when(view[1]):'the whole trace';apply();}
function when(v){if(ax==='lines')return 'line '+Math.round(v);if(ax==='seconds')return v.toFixed(3)+' s';var t=base+v,iso=utc(t);if(!iso)return t.toFixed(3)+' s';return (oneday?'':iso.slice(0,10)+' ')+iso.slice(11,23);}
function zoom(f,c){var a=view[0],b=view[1];if(c===undefined)c=(a+b)/2;var min=(all[1]-all[0])*1e-6;var na=c-(c-a)*f,nb=c+(b-c)*f;if(nb-na<min)return;set(na,nb);}
function set(a,b){var w=Math.min(b-a,all[1]-all[0]);if(a<all[0]){a=all[0];}if(a+w>all[1])a=all[1]-w;view=[a,a+w];redraw();}
// One layout per frame however many wheel events; the timer runs it where
// no frames are drawn (a background tab, a headless browser).
var pending=false;function redraw(){if(pending)return;pending=true;var f=function(){if(pending){pending=false;layout();}};requestAnimationFrame(f);setTimeout(f,100);}
function at(ev){var r=svg.getBoundingClientRect();return ev.clientX-r.left;}
svg.addEventListener('wheel',function(ev){var x=at(ev);if(x<X0||x>X1)return;ev.preventDefault();zoom(Math.exp(ev.deltaY*.002),view[0]+(x-X0)/(X1-X0)*(view[1]-view[0]));});
svg.addEventListener('mousedown',function(ev){var x=at(ev);if(x<X0||x>X1||ev.button!==0)return;drag=[x,view[0],view[1]];moved=false;ev.preventDefault();});
window.addEventListener('mousemove',function(ev){if(!drag)return;var dx=at(ev)-drag[0];if(Math.abs(dx)>3)moved=true;if(!moved)return;
var k=(drag[2]-drag[1])/(X1-X0);set(drag[1]-dx*k,drag[2]-dx*k);});
window.addEventListener('mouseup',function(){drag=null;});
svg.addEventListener('dblclick',function(){set(all[0],all[1]);});
var bar=document.createElement('p');bar.className='zoom';
[['+','zoom in',function(){zoom(.5);}],['−','zoom out',function(){zoom(2);}],['whole trace','show the whole trace',function(){set(all[0],all[1]);}]].forEach(function(b){
var e=document.createElement('button');e.textContent=b[0];e.title=b[1];e.addEventListener('click',b[2]);bar.appendChild(e);});
var range=document.createElement('span');range.className='note';bar.appendChild(range);
var hint=document.createElement('span');hint.className='note';hint.textContent=' · wheel: zoom, drag: pan, double-click: whole trace';bar.appendChild(hint);
box.parentNode.insertBefore(bar,box);
fit=layout;window.addEventListener('resize',redraw);}
// Rows: the node chosen (or all) within the visible time range, PAGE at a
// time; a new choice or range starts at the first page, the pager turns.
var PAGE=1000,page=0,prev=null,next=null;
function apply(turn){if(!tb)return;if(turn!==true)page=0;var m=0,from=page*PAGE,z=view&&(view[0]>all[0]||view[1]<all[1]);
[].forEach.call(tb.rows,function(r){var v=r.getAttribute('data-v'),out=z&&v!==null&&(+v<view[0]||+v>view[1]);
var match=!out&&(sel.value===''||r.getAttribute('data-lane')===sel.value);r.hidden=!(match&&m>=from&&m<from+PAGE);if(match)m++;});
sec.querySelectorAll('g.lane').forEach(function(g){g.style.opacity=sel.value===''||g.getAttribute('data-lane')===sel.value?'':'0.3';});
var k=tb.parentNode.getAttribute('data-every');
shown.textContent=(m>PAGE?'rows '+(from+1)+'–'+Math.min(from+PAGE,m)+' of '+m:m+' row'+(m===1?'':'s'))+' shown'+(z?' (in the visible time range)':'')+(k?'; the page carries every '+k+' event':'');
if(prev){prev.hidden=page===0;next.hidden=from+PAGE>=m;}}
if(tb&&tb.rows.length>PAGE){[['‹ previous '+PAGE,-1],['next '+PAGE+' ›',1]].forEach(function(b){
var e=document.createElement('button');e.textContent=b[0];e.className=b[1]<0?'prev':'next';e.addEventListener('click',function(){page+=b[1];apply(true);});
shown.parentNode.appendChild(e);if(b[1]<0)prev=e;else next=e;});}
if(sel&&tb){sel.addEventListener('change',apply);
sec.querySelectorAll('g.lane').forEach(function(g){g.addEventListener('click',function(){if(moved){moved=false;return;}var v=g.getAttribute('data-lane');sel.value=sel.value===v?'':v;apply();});});
var heads=sec.querySelectorAll('th');
heads.forEach(function(th,i){th.addEventListener('click',function(){
var up=th.getAttribute('data-dir')!=='asc';heads.forEach(function(h){h.removeAttribute('data-dir');});th.setAttribute('data-dir',up?'asc':'desc');
function key(r){var c=r.cells[i];return c.hasAttribute('data-k')?c.getAttribute('data-k'):c.textContent;}
var rows=[].slice.call(tb.rows);
rows.sort(function(a,b){var x=key(a),y=key(b),nx=parseFloat(x),ny=parseFloat(y),d;
d=(!isNaN(nx)&&!isNaN(ny)&&String(nx)===x&&String(ny)===y)?nx-ny:x.localeCompare(y);return up?d:-d;});
rows.forEach(function(r){tb.appendChild(r);});apply();});});}
if(fit)fit();else apply();});
"#;

fn write_section(s: &mut String, sec: &Section) -> std::fmt::Result {
    s.push_str("<section class=\"input\">\n<div class=\"chart\">\n");
    s.push_str(&document(&[&sec.panel], "", false));
    s.push_str("</div>\n<h2>Events</h2>\n");
    if sec.events == 0 {
        s.push_str("<p class=\"note\">No EMCY, boot-up or node-health events.</p>\n</section>\n");
        return Ok(());
    }
    s.push_str("<p><label>Node: <select><option value=\"\">all</option>");
    for (key, label) in &sec.panel.lanes {
        write!(s, "<option value=\"{}\">{}</option>", esc(key), esc(label))?;
    }
    s.push_str("</select></label> <span class=\"shown note\"></span></p>\n");
    // `data-every`: the page carries every n-th event only (`2nd`), so the
    // script says so beside the rows a zoom shows.
    let thinned = if sec.stride > 1 {
        format!(" data-every=\"{}\"", ordinal(sec.stride))
    } else {
        String::new()
    };
    write!(
        s,
        "<table class=\"ev\"{thinned}><thead><tr><th>{}</th><th>line</th><th>channel</th><th>node</th>\
         <th>event</th><th title=\"transition: 1 first error, 2 one error reset, 3 further error, 4 all reset\">TR</th>\
         <th>register</th><th>description</th><th>manufacturer</th><th>warnings</th><th>cleared</th><th>state after</th></tr></thead>\n<tbody>\n",
        sec.panel.clock.heading()
    )?;
    for r in &sec.rows {
        write_row(s, &sec.panel.clock, r)?;
    }
    s.push_str("</tbody></table>\n");
    if sec.stride > 1 {
        writeln!(
            s,
            "<p class=\"note\">This page lists every {} event of this input ({} of {}), spread \
             over the whole trace so that the list follows a zoom. The chart draws all of them; \
             <code>--format table</code> or <code>--format ndjson</code> lists every event.</p>",
            ordinal(sec.stride),
            sec.rows.len(),
            sec.events
        )?;
    }
    s.push_str("</section>\n");
    Ok(())
}

/// `2nd`, `4th`, `32nd`: the English ordinal of `n`.
fn ordinal(n: u64) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

fn write_row(s: &mut String, clock: &Clock, r: &Row) -> std::fmt::Result {
    let (class, event) = match r.kind {
        Kind::Boot => (" class=\"boot\"", "boot-up".to_string()),
        Kind::Emcy(0) => (" class=\"reset\"", "0x0000".to_string()),
        Kind::Emcy(c) => ("", format!("0x{c:04X}")),
        Kind::Health(slug) => ("", slug.to_string()),
    };
    let class = match r.kind {
        Kind::Health(slug) => format!(" class=\"{slug}\""),
        _ => class.to_string(),
    };
    let register = match r.kind {
        Kind::Emcy(_) => format!("0x{:02X}", r.register),
        _ => String::new(),
    };
    // The value on the time scale, for the script's visible-range filter.
    let v = clock
        .value(&At {
            time: r.time,
            line: r.line,
        })
        .map_or_else(String::new, |v| format!(" data-v=\"{v}\""));
    write!(
        s,
        "<tr{class} data-lane=\"{}\"{v}><td data-k=\"{}\">{}</td><td class=\"n\">{}</td><td>{}</td><td class=\"n\">{}</td>\
         <td>{event}</td><td class=\"n\">{}</td><td>{register}</td><td class=\"t\">{}</td><td class=\"t\">{}</td><td class=\"w\">",
        esc(&chart::lane_key(&r.channel, r.node)),
        r.line,
        esc(&clock.cell(r.time)),
        r.line,
        esc(&r.channel),
        r.node,
        r.transition
            .map_or_else(|| "-".to_string(), |t| t.to_string()),
        esc(&r.description),
        esc(&r.manufacturer),
    )?;
    // The tag in the cell, the whole text on hover.
    for (i, (tag, text)) in r.warnings.iter().enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        write!(s, "<span title=\"{}\">{tag}</span>", esc(text))?;
    }
    writeln!(
        s,
        "</td><td>{}</td><td>{}</td></tr>",
        codes_list(&r.cleared),
        r.state
    )
}

impl<W: Write> Sink for HtmlReport<W> {
    fn begin_input(&mut self, _file: &str) -> io::Result<()> {
        self.collector.begin_input();
        self.rows.clear();
        self.events = 0;
        self.stride = 1;
        Ok(())
    }

    fn emcy(&mut self, ev: &EmcyEvent<'_>) -> io::Result<()> {
        self.collector.emcy(ev);
        self.keep(|| Row {
            time: ev.time,
            line: ev.line,
            channel: ev.channel.to_string(),
            node: ev.node,
            kind: Kind::Emcy(ev.emcy.code),
            register: ev.emcy.register.0,
            transition: ev.transition,
            description: ev.description.to_string(),
            manufacturer: manufacturer_cell(ev.decoded, ev.data),
            warnings: ev
                .warnings
                .iter()
                .map(|w| (w.tag(), w.to_string()))
                .collect(),
            cleared: ev.cleared.to_vec(),
            state: ev.state.slug(),
        });
        Ok(())
    }

    fn health(&mut self, ev: &HealthEvent<'_>) -> io::Result<()> {
        self.collector.health(ev);
        self.keep(|| Row {
            time: ev.time,
            line: ev.line,
            channel: ev.channel.to_string(),
            node: ev.node,
            kind: Kind::Health(ev.health.slug()),
            register: 0,
            transition: None,
            // The same words as the table and CSV (times there in ISO-8601).
            description: health_text(ev.health),
            manufacturer: String::new(),
            warnings: Vec::new(),
            cleared: Vec::new(),
            // The column is the error state; an NMT state is in the text.
            state: "",
        });
        Ok(())
    }

    fn boot(&mut self, ev: &BootEvent<'_>) -> io::Result<()> {
        self.collector.boot(ev);
        self.keep(|| Row {
            time: ev.time,
            line: ev.line,
            channel: ev.channel.to_string(),
            node: ev.node,
            kind: Kind::Boot,
            register: 0,
            transition: None,
            description: "NMT boot-up: the node restarted".to_string(),
            manufacturer: String::new(),
            warnings: Vec::new(),
            cleared: ev.cleared.to_vec(),
            state: "error_free",
        });
        Ok(())
    }

    /// Incidents become numbered bands on the chart.
    fn bus(&mut self, ev: &BusEvent<'_>) -> io::Result<()> {
        self.collector.bus(ev);
        Ok(())
    }

    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        let panel = self.collector.end_input(input)?;
        self.sections.push(Section {
            panel,
            rows: std::mem::take(&mut self.rows),
            events: self.events,
            stride: self.stride,
        });
        Ok(())
    }

    fn finish(&mut self, inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        let title = doc_title(inputs);
        let mut s = String::with_capacity(64 * 1024);
        s.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        s.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        s.push_str(&format!("<title>{}</title>\n<style>\n", esc(&title)));
        s.push_str(PAGE_STYLE);
        let panels: Vec<&Panel> = self.sections.iter().map(|s| &s.panel).collect();
        s.push_str(&style_sheet(&panels));
        s.push_str("</style>\n</head>\n<body>\n<h1>EMCY timeline</h1>\n");
        if self.sections.is_empty() {
            s.push_str("<p class=\"note\">No input could be read.</p>\n");
        }
        for sec in &self.sections {
            write_section(&mut s, sec)
                .map_err(|_| io::Error::other("formatting the page failed"))?;
        }
        s.push_str("<script>\n");
        s.push_str(SCRIPT);
        s.push_str("</script>\n</body>\n</html>\n");
        self.out.write_all(s.as_bytes())?;
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyze::HistoryReport;
    use crate::analyze::event::HistoryItem;

    fn row_at(line: u64) -> Row {
        Row {
            time: None,
            line,
            channel: String::new(),
            node: 5,
            kind: Kind::Boot,
            register: 0,
            transition: None,
            description: String::new(),
            manufacturer: String::new(),
            warnings: Vec::new(),
            cleared: Vec::new(),
            state: "",
        }
    }

    #[test]
    fn a_long_input_keeps_every_nth_event_evenly_in_bounded_rows() {
        let mut page = HtmlReport::new(Vec::new());
        let events = PAGE_ROWS as u64 * 4 + 3;
        for line in 0..events {
            page.keep(|| row_at(line));
            assert!(page.rows.len() <= PAGE_ROWS, "at {line}");
        }
        // Thinned at 10 000, 20 000 and 40 000 events.
        assert_eq!(page.stride, 8);
        assert_eq!(page.rows.len(), PAGE_ROWS / 2 + 1);
        for (i, row) in page.rows.iter().enumerate() {
            assert_eq!(row.line, i as u64 * 8);
        }
        // Up to the bound, every event.
        let mut short = HtmlReport::new(Vec::new());
        for line in 0..PAGE_ROWS as u64 {
            short.keep(|| row_at(line));
        }
        assert_eq!((short.stride, short.rows.len()), (1, PAGE_ROWS));
    }

    #[test]
    fn ordinals_read_as_english() {
        let said: Vec<String> = [1, 2, 3, 4, 11, 12, 13, 21, 22, 32, 64, 101, 112, 1024]
            .into_iter()
            .map(ordinal)
            .collect();
        assert_eq!(
            said,
            [
                "1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "32nd", "64th",
                "101st", "112th", "1024th"
            ]
        );
    }

    #[test]
    fn manufacturer_cell_joins_a_text_to_its_number_else_shows_the_bytes() {
        let decoded = Decoded {
            fields: vec![
                ("category".to_string(), FieldValue::Int(1)),
                (
                    "category_text".to_string(),
                    FieldValue::Text("cleared only by a reset".to_string()),
                ),
                ("fault".to_string(), FieldValue::Int(235)),
                // A text without its number stays an item of its own.
                ("axis_text".to_string(), FieldValue::Text("A".to_string())),
            ],
        };
        assert_eq!(
            manufacturer_cell(Some(&decoded), &[0x10, 0x43, 0x08, 1, 0, 0, 0, 0]),
            "category: 1 (cleared only by a reset); fault: 235; axis_text: A"
        );
        let raw = [0x30, 0x81, 0x11, 0x1B, 0x05, 0, 0, 0];
        assert_eq!(manufacturer_cell(None, &raw), "1B05000000");
        assert_eq!(
            manufacturer_cell(None, &[0x30, 0x81, 0x11, 0, 0, 0, 0, 0]),
            ""
        );
        // A short frame has what it has.
        assert_eq!(manufacturer_cell(None, &[0x30, 0x81]), "");
    }

    #[test]
    fn an_error_history_lists_its_entries() {
        let h = Health::ErrorHistory(HistoryReport {
            entries: vec![
                HistoryItem {
                    code: 0x4310,
                    info: 0x12,
                    description: "excess temperature drive".to_string(),
                    before_trace: true,
                },
                HistoryItem {
                    code: 0x3120,
                    info: 0,
                    description: "mains under-voltage".to_string(),
                    before_trace: false,
                },
            ],
            count: Some(2),
            complete: true,
            time: None,
            line: 7,
        });
        let text = health_text(&h);
        assert!(
            text.ends_with(
                ": 0x4310 excess temperature drive (info 0x0012), before the trace; \
                 0x3120 mains under-voltage"
            ),
            "{text}"
        );
        assert_eq!(
            health_text(&Health::ErrorHistoryCleared),
            "error history cleared"
        );
    }
}
